// paths/ orientation (seed 000, issue 24): the full impeller (7 veins x 61 passes, ~80 mm each, a
// 500-node tool, as cases/orient_impeller.toml), on the voxel field (goal: under 60 s here) and by the
// direct sum (goal: under 10 min);
// the seed took 54 h 48 min direct and 59-75 min with voxels (MATLAB, Xeon E5-1620 3.6 GHz, Tables 3.2
// and 4.1). Prints one JSON object per run with the split: precompute, poses, clearance check.
//   build/bench/orient_bench [voxel|direct] [veins] [voxel_mm]     (results: docs/orientation.md)
//   build/bench/orient_bench CASE.toml OUT [key=value ...]          (one case, timed, with drom orient's files)
#include "paths/orient/orient_run.hpp"

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

int main(int argc, char** argv) {
  if (argc > 2 && std::string(argv[1]).ends_with(".toml")) {
    const auto t0 = std::chrono::steady_clock::now();
    const drom::paths::OrientCase c = drom::paths::load_orient_case(argv[1], std::vector<std::string>(argv + 3, argv + argc));
    const auto result = drom::paths::run_orient(c, {argv[2], false, true});
    std::printf("{\"case\": \"%s\", \"total_s\": %.2f, \"timing_s\": %s}\n", argv[1],
                std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(), result.summary["timing_s"].dump().c_str());
    return 0;
  }
  const std::string field = argc > 1 ? argv[1] : "voxel";
  const std::string veins = argc > 2 ? argv[2] : "-1";
  const std::string voxel = argc > 3 ? argv[3] : "1.0";
  const auto t0 = std::chrono::steady_clock::now();
  const drom::paths::OrientCase c = drom::paths::parse_orient_case(
      "[scene]\nkind = \"impeller\"\n[tool]\nnodes = 500\n[model]\nsingular_cone = 0.0873\n", "<bench impeller>",
      {"scene.veins=" + veins, "field.kind=" + field, "field.voxel=" + voxel});
  const auto result = drom::paths::run_orient(c, {"", true, false});
  const double total = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  const auto& s = result.summary;
  std::printf("{\"field\": \"%s\", \"voxel_mm\": %s, \"passes\": %d, \"path_length_mm\": %.0f, \"obstacle_nodes\": %d, \"tool_nodes\": %d, "
              "\"distance_field_s\": %.2f, \"voxel_field_s\": %.2f, \"poses_s\": %.2f, \"clearance_check_s\": %.2f, \"total_s\": %.2f, "
              "\"rhs_evaluations\": %ld, \"threads\": %d, \"cycle_time_programmed_s\": %.1f, \"cycle_time_after_s\": %.1f, \"worst_clearance_mm\": %.3f, \"collisions\": %d, \"programmed_axis_collisions\": %d, \"unreachable_poses\": %zu}\n",
              field.c_str(), voxel.c_str(), s["scene"]["passes"].get<int>(), s["scene"]["path_length_mm"].get<double>(),
              s["model"]["obstacle_nodes"].get<int>(), s["model"]["tool_nodes"].get<int>(), s["timing_s"]["distance_field"].get<double>(),
              s["timing_s"]["voxel_field"].get<double>(), s["timing_s"]["poses"].get<double>(), s["timing_s"]["clearance_check"].get<double>(), total,
              s["model"]["rhs_evaluations"].get<long>(), s["timing_s"]["threads"].get<int>(), s["machine"]["cycle_time_programmed_s"].get<double>(),
              s["machine"]["cycle_time_after_s"].get<double>(), s["clearance"]["after"]["worst_clearance_mm"].get<double>(),
              s["clearance"]["after"]["collisions"].get<int>(), s["clearance"]["programmed_axis"]["collisions"].get<int>(), result.unreachable.size());
  return 0;
}
