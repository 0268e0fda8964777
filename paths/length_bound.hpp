#pragma once
// The shortest cutting length a parallel-plane finishing path can have on a surface under the seed's
// step-over model (Herraz eqs. 1.5 and 2.3), whatever its zones and feed directions.
//
// Passes a step w apart cover w mm² of surface per mm of pass, and the widest step eq. 2.3 allows
// at a point is the one at the largest effective radius: the torus fed along the point's own
// steepest slope (alpha = 0 in eq. 1.5, capped by its level-ground step), the ball's R. So the
// passes together are at least the integral of dA / w_max(x) long. The worst-point rule (the step of
// a whole plane is its least favourable point's), feeds off the local steepest slope, pass ends and
// links only add. Dividing by the feed gives a floor on the cutting time (no acceleration).
//
// The bound is one of the seed's model: on curved ground drom's default step (curved_stepover,
// swept_profile) differs from eq. 2.3, so it bounds `finish.stepover = "seed"` and `"flat"` paths.
// docs/finishing.md section 3 uses it to show that some of the seed's chapter-3 lengths lie below it.
#include "geometry/nurbs_surface.hpp"
#include "geometry/trim_loops.hpp"
#include "paths/move_time.hpp"
#include "paths/tool.hpp"

#include <Eigen/Core>

namespace drom::paths {

struct CuttingLengthBound {
  double area = 0;    // mm², of the face (inside its trim loops)
  double length = 0;  // mm, the shortest total length of the passes
  double time = 0;    // s, that length at the feed
};

// Midpoint rule on a cells x cells parametric grid; the slope is taken against `axis` (3-axis: Z).
// Throws std::domain_error where the surface has no normal, std::invalid_argument for sh outside
// (0, r] or fewer than one cell.
CuttingLengthBound shortest_cutting_length(const geometry::NurbsSurface& surface, const geometry::TrimLoops& trim, const Tool& tool, double scallop,
                                           const Kinematics& limits, int cells = 200, const Eigen::Vector3d& axis = Eigen::Vector3d::UnitZ());

}  // namespace drom::paths
