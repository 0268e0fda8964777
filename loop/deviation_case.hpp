#pragma once
// A blank-deviation case (seed chapter 2): the area of interest, the deviation family, the true
// blank, the laser sheet and its errors, the approach and the passes, the learning criteria. Read
// from TOML with the same checks as machining cases (docs/deviation.md lists every key).
#include "online/laser_sheet.hpp"
#include "reduce/deviation_family.hpp"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace drom::loop {

struct DeviationCase {
  std::string name, description, origin, resolved_toml;
  reduce::DeviationGrid grid;
  double nominal_z = 0;
  reduce::DeviationRange seed_a, seed_b, bending_x, bending_y, twist, offset, tilt_x, tilt_y;
  std::vector<std::filesystem::path> measured;
  double family_tolerance = 1e-3;
  std::string truth = "seed";
  std::filesystem::path truth_csv;
  online::LaserSheet sheet;
  online::SensorErrors errors;
  double period = 0.1, desync = 0, feed_override = 1;
  double feed = 10, stepover = 20;
  std::vector<double> approach_x, approach_y;
  double learning_tolerance = 0.01, path_tolerance = 0.02;
  int learning_window = 5;
};

DeviationCase load_deviation_case(const std::filesystem::path& path, const std::vector<std::string>& overrides);

}  // namespace drom::loop
