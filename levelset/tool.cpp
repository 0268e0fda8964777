#include "levelset/tool.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace drom::levelset {

Tool Tool::flat(double radius, double flute_length) { return {ToolKind::Flat, radius, 0.0, flute_length}; }
Tool Tool::ball(double radius, double flute_length) { return {ToolKind::Ball, radius, radius, flute_length}; }
Tool Tool::bull_nose(double radius, double corner_radius, double flute_length) {
  if (!(corner_radius > 0 && corner_radius < radius)) throw std::invalid_argument("bull-nose: 0 < corner radius < radius");
  return {ToolKind::BullNose, radius, corner_radius, flute_length};
}

double Tool::section_radius(double h) const {
  if (h < 0 || h > flute_length) return 0;
  const double r = corner_radius;
  if (h >= r) return radius;
  return (radius - r) + std::sqrt(std::max(0.0, r * r - (r - h) * (r - h)));
}

double Tool::bottom_height(double rho) const {
  const double flat = radius - corner_radius;
  rho = std::abs(rho);
  if (rho <= flat) return 0;
  const double d = std::min(rho - flat, corner_radius);
  return corner_radius - std::sqrt(std::max(0.0, corner_radius * corner_radius - d * d));
}

double Tool::signed_distance(double rho, double h) const {
  // Rounded box: core [-a, a] x [r, top] dilated by r, then cut by h <= flute_length.
  const double r = corner_radius, a = radius - corner_radius;
  const double top = flute_length + r;  // the core reaches past the cut so the top stays flat
  const double cx = 0, cy = 0.5 * (r + top);
  const double qx = std::abs(std::abs(rho) - cx) - a;
  const double qy = std::abs(h - cy) - 0.5 * (top - r);
  const double ox = std::max(qx, 0.0), oy = std::max(qy, 0.0);
  const double outside = std::sqrt(ox * ox + oy * oy);  // lengths in mm: no overflow for hypot to guard against
  const double rounded = outside + std::min(std::max(qx, qy), 0.0) - r;
  return std::max(rounded, h - flute_length);
}

double signed_distance(const Tool& tool, const ToolPose& pose, const Eigen::Vector3d& x) {
  const Eigen::Vector3d d = x - pose.tip;
  const double h = d.dot(pose.axis);
  return tool.signed_distance((d - h * pose.axis).norm(), h);
}

double swept_signed_distance(const Tool& tool, const Eigen::Vector3d& axis, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& x, double tolerance) {
  const Eigen::Vector3d ab = b - a;
  const double along_axis = ab.dot(axis);
  const Eigen::Vector3d lateral = ab - along_axis * axis;
  if (std::abs(along_axis) <= 1e-12 * std::max(1.0, ab.norm())) {
    // Move perpendicular to the axis: the tool's distance grows with rho at fixed h (convex solid of
    // revolution), so the nearest tool position is the one nearest to x across the axis.
    const Eigen::Vector3d d = x - a;
    const double h = d.dot(axis);
    const Eigen::Vector3d d_lat = d - h * axis;
    const double len2 = lateral.squaredNorm();
    const double t = len2 > 0 ? std::clamp(d_lat.dot(lateral) / len2, 0.0, 1.0) : 0.0;
    return tool.signed_distance((d_lat - t * lateral).norm(), h);
  }
  // General segment: the distance is convex along it; golden-section search.
  auto f = [&](double t) { return signed_distance(tool, {a + t * ab, axis}, x); };
  double lo = 0, hi = 1;
  const double g = 0.5 * (std::sqrt(5.0) - 1);
  double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo), f1 = f(x1), f2 = f(x2);
  const double t_tolerance = tolerance / std::max(1e-12, ab.norm());
  for (int it = 0; it < 80 && hi - lo > t_tolerance; ++it) {
    if (f1 < f2) {
      hi = x2;
      x2 = x1;
      f2 = f1;
      x1 = hi - g * (hi - lo);
      f1 = f(x1);
    } else {
      lo = x1;
      x1 = x2;
      f1 = f2;
      x2 = lo + g * (hi - lo);
      f2 = f(x2);
    }
  }
  return std::min({f(0.0), f(1.0), f(0.5 * (lo + hi))});
}

}  // namespace drom::levelset
