#pragma once
// A path on a cloud checked with the whole tool (cutter, shank, holder) against every point, apart
// from the drop that made it: at each path point and at points every `spacing` along each move, how
// deep the solid tool stands inside the cloud (or the obstacles' surfaces). A cut node the planner
// dropped (with its contact normal) stands at its drop by construction and is not dropped again
// (unless the move to it is a single sample). The finishing's straight
// moves may dip by the chord tolerance; rapids and roughing moves must not dip at all.
#include "geometry/cloud_bins.hpp"
#include "paths/copy/cloud_path.hpp"
#include "paths/cutter/tool_assembly.hpp"

#include <Eigen/Core>

#include <string>

namespace drom::paths {

struct PathCheck {
  long long positions = 0;   // tool positions checked
  double deepest = 0;        // mm: the deepest any point stands inside the tool (0 when none does)
  Eigen::Vector3d worst = Eigen::Vector3d::Zero();  // the tip there (drop frame)
  long long over = 0;        // positions deeper than the tolerance
};

// `bins`: the collision points in the path's drop frame. `tolerance`: the depth a cut or link move may
// reach (the chord tolerance); rapids are held to 0.
PathCheck check_path(const geometry::CloudBins& bins, const CloudPath& path, const ToolAssembly& tool, double spacing, double tolerance);

// Why a checked path must not be posted (issue 45: a move known to leave the tolerance is a refusal, not
// a number in summary.json): how many positions stand deeper than `tolerance`, the deepest, and its tip
// in the part frame (`frame`: drop = frame * part). Empty when none does.
std::string refusal(const PathCheck& check, const Eigen::Matrix3d& frame, double tolerance);

}  // namespace drom::paths
