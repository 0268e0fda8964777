#pragma once
// One closed-loop parameter swept, everything else as the case says (drom study). The offline database,
// model and truth are drom run's (the same options.out reuses them: no swept parameter changes them);
// per value, the loop with and without correction; study.csv, study.png and summary.json. The stress
// amplitude scales the truth's displacements (linear in the stresses), so it reruns nothing either.
#include "loop/closed_loop_setup.hpp"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace drom::loop {

// The parameters a study can sweep: noise, angle, refresh, calibration, desync, amplitude, seed.
std::vector<std::string> study_parameters();

// Returns the summary; its "rows" hold each value's headline figures. Throws InputError for an
// unknown parameter or no value.
nlohmann::json run_study(const case_file::Case& base, const std::string& parameter, const std::vector<double>& values, const RunOptions& options);

}  // namespace drom::loop
