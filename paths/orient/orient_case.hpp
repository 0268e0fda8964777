#pragma once
// The orient case (docs/case-files.md, "drom orient"): [scene], [tool], [model], [integration],
// [field], [check], [machine] and [[check_surfaces]], read and checked (InputError with file, line and
// key), and the scene it asks for, built once the read has checked its size.
#include "machine/post_processor.hpp"
#include "paths/orient/axis_dynamics.hpp"
#include "paths/orient/clearance_check.hpp"
#include "paths/orient/force_voxel_field.hpp"
#include "paths/orient/orient_scene.hpp"
#include "paths/orient/orientation_under_limits.hpp"

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
  machine::PostOptions program;  // the [program] table (machine/program_keys.hpp); the tool's diameter is set when posting
  std::optional<Eigen::Vector3d> part_origin;  // machine.part_origin: the scene's own when unset
  bool model_on = true;            // false: the programmed axis only (what the clearance check flags)
  // [relax]: also the programmed axis relaxed under the machine's limits (thesis 003, eq. 5), checked
  // and reported beside the field's result; empty: not asked.
  std::optional<RelaxationSettings> relax;
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

}  // namespace drom::paths
