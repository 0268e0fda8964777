#pragma once
// The shortest cutting length a parallel-plane finishing path can have on a surface if it keeps the
// seed's flat-ground scallop bound (Herraz eq. 2.3, with eq. 1.5's effective radius) at every point
// and covers the surface out to its edges, whatever its zones and feed directions.
//
// Passes a step w apart cover w mm² of surface per mm of pass, and the widest step eq. 2.3 allows
// at a point is the one at the largest effective radius: the torus fed along the point's own
// steepest slope (alpha = 0 in eq. 1.5; drom caps it by the torus's level-ground step, which binds
// only below a fraction of a degree of slope), the ball's R. So the passes together are at least
// the integral of dA / w_max(x) long, to first order in the step (a step that changes across a
// strip lets discrete passes gain a fraction of a percent). Dividing by the feed gives a floor on
// the cutting time (no acceleration).
//
// What the bound does not cover: drom's curved step-over may step wider on concave ground; the
// seed's worst-point rule may step wider than eq. 2.3 where the surface tilts across the pass; its
// edge convention may leave up to half a step uncut at a zone's far edge (docs/finishing.md §3, §5).
#include "geometry/nurbs_surface.hpp"
#include "geometry/trim_loops.hpp"
#include "paths/finish/move_time.hpp"
#include "paths/cutter/tool.hpp"

#include <Eigen/Core>

namespace drom::paths {

struct CuttingLengthBound {
  double area = 0;    // mm², of the face (inside its trim loops)
  double length = 0;  // mm, the shortest total length of the passes
  double time = 0;    // s, that length at the feed
};

// Midpoint rule on a cells x cells parametric grid (a cell counts where its centre lies inside the
// trim loops); the slope is taken against `axis` (3-axis: Z). Throws std::domain_error where the
// surface has no normal, std::invalid_argument for sh outside (0, r], a feed that is not positive,
// an axis that is zero or not finite, or fewer than one cell.
CuttingLengthBound shortest_cutting_length(const geometry::NurbsSurface& surface, const geometry::TrimLoops& trim, const Tool& tool, double scallop,
                                           const Kinematics& limits, int cells = 200, const Eigen::Vector3d& axis = Eigen::Vector3d::UnitZ());

}  // namespace drom::paths
