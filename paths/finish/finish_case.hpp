#pragma once
// A finishing case: the surface ([surface], read by geometry/surface_input.hpp), the tool, the
// machine's limits (the stand-in for machine/'s definitions), the finishing settings and the zoning
// (docs/case-files.md, "Finishing cases"). Read with the same checks as every drom case: unknown
// keys are errors, and errors name the file, the line and the key.
#include "geometry/surface_input.hpp"
#include "machine/post_processor.hpp"
#include "paths/finish/clustering.hpp"
#include "paths/finish/finish_optimizer.hpp"
#include "paths/finish/zone_machining.hpp"

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace drom::paths {

struct FinishCase {
  std::string name, description, origin, resolved_toml;
  geometry::SurfaceInput surface;
  bool auto_tool = false;           // the PCA verdict picks ball or torus
  Tool ball{ToolKind::ball, 5, 5}, torus{ToolKind::torus, 5, 2};
  FinishingSettings settings;       // the tool in it is the case's (the torus when auto, until the verdict)
  std::string machine_definition;   // machine/'s definition (a file or a shipped name): times and posts the program
  machine::PostOptions program;     // the [program] table (machine/program_keys.hpp); the tool's diameter is set when posting
  int samples = 80;                 // clustering grid, per side
  double mesh_step = 0.5;           // mm
  SetupMode setup = SetupMode::three_axis;
  std::optional<Eigen::Vector2d> orientation;  // a fixed tool axis (phi, psi), radians: 3+2 without zoning
  std::string orientation_where;                // where it was given ("case.toml:31: finish.orientation"), for errors found when planning
  // Zoning: optimised over K in [clusters_min, clusters_max], or one partition.
  bool optimize = true;
  int clusters_min = 2, clusters_max = 10;
  std::string algorithm = "kmeans";  // kmeans, rpcl, ward (without optimisation)
  ClusteringSettings clustering;
  std::uint64_t rpcl_seed = 1;
  double budget = 1000;
  bool surrogate = true;
};

FinishCase load_finish_case(const std::filesystem::path& path, const std::vector<std::string>& overrides);

}  // namespace drom::paths
