#pragma once
// `drom orient CASE`: the collision-free tool-axis orientation of seed 000 on a case, proved and put on
// a machine. Reads the case ([scene], [tool], [model], [integration], [field], [check], [machine],
// [[check_surfaces]]; docs/case-files.md), meshes the obstacles and the tool, integrates every pass,
// checks clearance and gouging of the result (and of the programmed axis, to show what the model
// avoids), maps both onto the machine (axis velocity, acceleration and jerk against the limits, the
// predicted cycle time) and writes, in `out`:
//   cl.csv, program.ngc     the corrected CL data and its 5-axis G-code (machine/'s post-processor)
//   path.vtp                the CL path with θ, clearance, gouge and the axes (programmed and corrected)
//   poses.vtp               the tool's axis as a segment tip → holder top every few mm
//   angles.csv, angles.png  θ, θ̇, θ̈, θ⃛ along s (per pass)
//   axes.csv                the rotary axes along s at the feed: position, velocity, acceleration, jerk
//   relaxed_cl.csv          with [relax]: the programmed axis relaxed under the machine's limits
//   summary.json            the figures, the timing split (precompute, poses, clearance check)
#include "paths/orient/orient_case.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace drom::paths {

struct OrientOptions {
  std::filesystem::path out = "out/orient";
  bool quiet = false;
  bool write_files = true;  // false: compute and return the summary only (tests, benchmark)
  int threads = 0;          // passes integrated and poses checked at once; 0: one per hardware thread
};

struct OrientResult {
  nlohmann::json summary;
  std::vector<AxisHistory> passes;
  ClearanceReport after, before;  // the corrected and the programmed axes
  // Poses of the corrected axis the machine cannot reach (a stroke, a rotary limit): reported, with the
  // rest of the result written, rather than thrown away after the whole computation. No G-code then.
  std::vector<std::string> unreachable;
  // With [relax]: the programmed axis relaxed under the machine's limits, per pass (tip and axis at
  // each of the pass's points; empty for a pass the relaxation could not place), and its check.
  std::vector<std::vector<machine::ClPose>> relaxed;
  ClearanceReport relaxed_check;
};

// Throws InputError for bad input: a check surface crossing the CL path, a tool longer than the
// machine's Z stroke. Poses out of the machine's reach are reported (OrientResult::unreachable).
OrientResult run_orient(const OrientCase& c, const OrientOptions& options);

}  // namespace drom::paths
