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
//   summary.json            the figures, the timing split (precompute, poses, clearance check)
#include "paths/orient/axis_dynamics.hpp"
#include "paths/orient/clearance_check.hpp"
#include "paths/orient/force_voxel_field.hpp"
#include "paths/orient/orient_scene.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <variant>
#include <vector>

namespace drom::paths {

// The [scene] table as read: which scene and its parameters. The scene itself (surfaces sampled,
// passes placed for the case's tool) is built by build_orient_scene, after the read, so reading a case
// stays cheap and its size is checked before anything is allocated.
using SceneOptions = std::variant<BumpOptions, CornerOptions, ImpellerOptions, PanelOptions>;

struct OrientCase {
  std::filesystem::path origin;
  SceneOptions scene;
  std::vector<CheckPatch> extra_patches;  // [[check_surfaces]]: patches
  TriangleSoup extra_mesh;                // [[check_surfaces]]: STL triangles
  ToolAssembly tool;
  KhatibParameters khatib;
  Aggregation aggregation = Aggregation::F1;
  DynamicsSettings dynamics;
  double obstacle_spacing = 2;     // mm (d0 by default)
  int tool_nodes = 500;            // random nodes; 0: a skin at `skin_spacing`
  double skin_spacing = 1;
  bool voxel = false;
  VoxelFieldSettings voxel_settings;
  double smoothing = 0;  // mm: σ of the zero-phase filter of the result (smooth_axis); 0: off
  ClearanceSettings clearance;
  std::string machine = "ucp710_like";
  std::optional<Eigen::Vector3d> part_origin;  // machine.part_origin: the scene's own when unset
  bool model_on = true;            // false: the programmed axis only (what the clearance check flags)
  std::string resolved;            // the case after overrides
};

// Reads a case; InputError (file, line, key) for bad input, including a scene, tool skin or obstacle
// mesh too large to hold (limits below).
OrientCase load_orient_case(const std::filesystem::path& path, const std::vector<std::string>& overrides = {});
OrientCase parse_orient_case(const std::string& text, const std::string& origin, const std::vector<std::string>& overrides = {});

// What a case may ask for: past these a machine of this size runs out of memory or time. Each is
// several times what the shipped cases use.
struct OrientLimits {
  static constexpr double cl_points = 5e6;        // CL points in all passes (the full impeller: about 1e5)
  static constexpr double passes = 1e4;           // passes (the impeller: 427)
  static constexpr double tool_nodes = 1e6;       // skin nodes on the shank and holder
  static constexpr double obstacle_points = 2e7;  // check-surface points (the impeller at 2 mm: 1.1e4)
  static constexpr double voxels = 2e8;           // active voxels of the force field or of the distance check's band
};

// The scene the case asks for, its passes placed for the case's tool, with its extra check surfaces.
// Throws InputError when the obstacle mesh or a voxel grid would exceed OrientLimits.
OrientScene build_orient_scene(const OrientCase& c);

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
};

// Throws InputError for bad input: a check surface crossing the CL path, a tool longer than the
// machine's Z stroke. Poses out of the machine's reach are reported (OrientResult::unreachable).
OrientResult run_orient(const OrientCase& c, const OrientOptions& options);

}  // namespace drom::paths
