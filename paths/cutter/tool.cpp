#include "paths/cutter/tool.hpp"

#include <algorithm>
#include <cmath>
#include <sstream>

namespace drom::paths {

std::string Tool::name() const {
  std::ostringstream s;
  if (kind == ToolKind::ball) s << "ball R" << radius;
  else if (corner_radius == 0) s << "flat R" << radius;
  else s << "torus R" << radius << " r" << corner_radius;
  return s.str();
}

bool is_flat(const Tool& cutter) { return cutter.kind == ToolKind::torus && cutter.corner_radius == 0; }

double bottom_height(const Tool& cutter, double rho) {
  rho = std::abs(rho);
  if (cutter.kind == ToolKind::ball) return cutter.radius - std::sqrt(std::max(0.0, cutter.radius * cutter.radius - rho * rho));
  const double flat = cutter.radius - cutter.corner_radius;
  if (rho <= flat) return 0;
  const double d = rho - flat, r = cutter.corner_radius;
  return r - std::sqrt(std::max(0.0, r * r - d * d));
}

Eigen::Vector3d cutter_location(const Eigen::Vector3d& cc, const Eigen::Vector3d& n, const Tool& tool, const Eigen::Vector3d& axis) {
  if (tool.kind == ToolKind::ball) return cc + tool.radius * (n - axis);
  const double r = tool.corner_radius;
  Eigen::Vector3d tip = cc + r * (n - axis);
  const Eigen::Vector3d radial = n - n.dot(axis) * axis;
  if (radial.norm() > 1e-12) tip += (tool.radius - r) * radial.normalized();
  return tip;
}

}  // namespace drom::paths
