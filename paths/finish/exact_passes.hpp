#pragma once
// The exact variant of the parallel-plane passes: every contact point on the surface itself and on
// the cutting plane, by Newton's method (the seed's eq. 1.12 solves for the next point by Newton
// too, but lets it drift off the plane along the normal). The iso-line mesh still orders a pass's
// points: each crossing of the plane with an iso-line is solved on the true iso-curve, then midpoints
// are put on the true curve of intersection until every chord lies within `chord_tolerance` of it.
#include "geometry/nurbs_surface.hpp"

#include <Eigen/Core>

#include <functional>
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

// The plane's intersection with the surface traced on from a pass's end: from `start.point`
// (parameters near `start.uv`) in `start.direction`, on while `rules.needed` says so and
// `rules.margin` mm of arc beyond (at least the margin, at most `rules.max_length`), chords within
// `rules.chord_tolerance`. Past the patch's boundary the surface is its own boundary spans continued
// (a B-spline's polynomials are defined beyond its domain; that is the patch's smoothest extension,
// and the one OpenCASCADE's GeomLib::ExtendSurfByLength approximates). The trace stops early where
// the surface turns within about 6 degrees of parallel to `rules.axis` (a tool along it would no
// longer touch from above) or the intersection is lost. The end point itself is not repeated.
struct TracePoint {
  Eigen::Vector2d uv;
  geometry::SurfaceDerivatives derivatives;
  Eigen::Vector3d tangent, normal;
};
struct TraceStart {
  Eigen::Vector2d uv;                 // parameters at (or near) the point
  Eigen::Vector3d point;              // the pass's end
  Eigen::Vector3d direction;          // the way the pass leaves (any length)
  Eigen::Vector3d reference_normal;   // the machined side there
};
struct TraceRules {
  Eigen::Vector3d plane_normal = Eigen::Vector3d::UnitY();  // the pass's plane: plane_normal . x = level
  double level = 0;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();          // the tool's
  double margin = 0;           // mm of arc past the last point `needed` asked for
  double max_length = 0;       // mm of arc at most
  double chord_tolerance = 0;  // mm
  std::function<bool(const TracePoint&)> needed;  // empty: the margin only
};
std::vector<SurfaceContact> trace_on(const geometry::NurbsSurface& surface, TraceStart start, const TraceRules& rules);

}  // namespace drom::paths
