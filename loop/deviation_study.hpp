#pragma once
// An unknown blank's deviation learned from laser profiles during the approach and the first passes,
// and the tool's altitude corrected (drom deviation; docs/design.md §8, seed chapter 2):
//   1. the deviation family on the area's grid and its POD basis (tolerance-bounded, reduce/pod.hpp);
//   2. the program: the approach waypoints, then one-way passes along x; edges at every waypoint;
//   3. offline, the scan extent needed (each mode in turn as the true surface);
//   4. online, the simulated blank scanned at the sensor's period, with its noise, calibration errors,
//      desynchronization and feed override; learning ends when the extent is reached and the recent
//      profiles are predicted within the tolerance; then the altitude is corrected;
//   5. error maps (VTK, PNG), error along the path (CSV, PNG), summary.json, in `out`.
#include "loop/deviation_case.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>

namespace drom::loop {

// Returns the summary. Progress on stderr unless quiet.
nlohmann::json run_deviation_study(const DeviationCase& c, const std::filesystem::path& out, bool quiet);

}  // namespace drom::loop
