#pragma once
// Differential geometry at a surface point from its parametric derivatives: the unit normal, the
// slope and steepest-slope azimuth against an axis, the fundamental forms, Gaussian, mean and
// principal curvatures with their directions, and the curvature tensor that gives the normal
// curvature in any tangent direction.
#include "geometry/nurbs_surface.hpp"

#include <Eigen/Core>

#include <optional>

namespace drom::geometry {

struct LocalGeometry {
  Eigen::Vector3d point, normal;  // normal: (S_u x S_v) / |S_u x S_v|
  double area_element = 0;        // |S_u x S_v|
  double E = 0, F = 0, G = 0;     // first fundamental form
  double L = 0, M = 0, N = 0;     // second fundamental form, against `normal`
  double gaussian = 0, mean = 0;  // K and H (H > 0 where the surface bends towards `normal`)
  double kappa1 = 0, kappa2 = 0;  // principal curvatures, kappa1 >= kappa2
  Eigen::Vector3d direction1, direction2;  // unit principal directions (3D, tangent)
  // Normal curvature in a unit tangent direction t is t' * curvature * t (symmetric, zero on the normal).
  Eigen::Matrix3d curvature;
};

// Throws std::domain_error where the normal is undefined (S_u x S_v vanishes: a degenerate patch).
LocalGeometry local_geometry(const SurfaceDerivatives& d);

// Normal curvature in the unit tangent direction t.
inline double normal_curvature(const LocalGeometry& g, const Eigen::Vector3d& t) { return t.dot(g.curvature * t); }

// A normal oriented to the side of `axis` (n . axis >= 0).
inline Eigen::Vector3d normal_towards(const Eigen::Vector3d& normal, const Eigen::Vector3d& axis) { return normal.dot(axis) < 0 ? -normal : normal; }

// Slope: the angle between the normal and the axis, in [0, pi/2] (s = arccos |n . axis|), for a
// unit axis.
double slope(const Eigen::Vector3d& normal, const Eigen::Vector3d& axis);

// Steepest-slope azimuth: the angle from X to the XY projection of the normal, reduced modulo pi to
// [-pi/2, pi/2); the frame's Z is the axis. Zero on a horizontal tangent plane.
double steepest_azimuth(const Eigen::Vector3d& normal);

// The first (u, v) on a cells_u x cells_v grid of cell corners where S_u x S_v is shorter than
// `relative_tolerance` times the patch's size squared, if any: a degenerate (collapsed) patch.
std::optional<Eigen::Vector2d> find_degenerate_point(const NurbsSurface& surface, int cells_u, int cells_v, double relative_tolerance = 1e-9);

}  // namespace drom::geometry
