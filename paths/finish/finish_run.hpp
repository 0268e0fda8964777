#pragma once
// `drom finish CASE`: the surface described (PCA, the ball-or-torus verdict), zoned (optimised over K
// with the seed's black box, or one partition as the case asks), finished by parallel planes, timed,
// checked for its scallop, and written out (finish_outputs.hpp, summary.json, the optimisation
// history). Each K's optimisation is kept under out/optimization/ so a rerun of the same case
// resumes where it stopped.
#include "paths/finish/finish_case.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>

namespace drom::paths {

struct FinishRunOptions {
  std::filesystem::path out = "out";
  bool quiet = false;
  int threads = 0;  // 0: one per hardware thread (K values run in parallel)
};

nlohmann::json run_finish(const FinishCase& c, const FinishRunOptions& options);

}  // namespace drom::paths
