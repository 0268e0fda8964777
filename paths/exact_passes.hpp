#pragma once
// The exact variant of the parallel-plane passes: every contact point on the surface itself and on
// the cutting plane, by Newton's method (the seed's eq. 1.12 solves for the next point by Newton
// too, but lets it drift off the plane along the normal). The iso-line mesh still orders a pass's
// points: each crossing of the plane with an iso-line is solved on the true iso-curve, then midpoints
// are put on the true curve of intersection until every chord lies within `chord_tolerance` of it.
#include "geometry/nurbs_surface.hpp"

#include <Eigen/Core>

#include <vector>

namespace drom::paths {

// A crossing of the plane with an iso-parametric line: v fixed and u free in [lo, hi] (along_u), or
// u fixed and v free.
struct IsoCrossing {
  double u = 0, v = 0;
  bool along_u = true;
  double lo = 0, hi = 1;
};

struct SurfaceContact {
  Eigen::Vector3d point, normal;  // normal on the side of the reference normal given
  Eigen::Matrix3d curvature;      // against that normal
};

// The chain's points put on the surface and refined. `reference_normals` (one per crossing) pick the
// machined side.
std::vector<SurfaceContact> exact_chain(const geometry::NurbsSurface& surface, const Eigen::Vector3d& plane_normal, double level,
                                        const std::vector<IsoCrossing>& chain, const std::vector<Eigen::Vector3d>& reference_normals, double chord_tolerance);

}  // namespace drom::paths
