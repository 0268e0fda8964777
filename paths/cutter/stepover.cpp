#include "paths/cutter/stepover.hpp"

#include <cmath>
#include <limits>

namespace drom::paths {

double effective_radius(const Tool& tool, double slope, double alpha) {
  if (tool.kind == ToolKind::ball) return tool.radius;
  const double ss = std::sin(slope), sa = std::sin(alpha), ca = std::cos(alpha);
  const double denominator = ss * (1 - sa * sa * ss * ss);
  if (!(denominator > 0)) return ca * ca > 0 ? std::numeric_limits<double>::infinity() : tool.corner_radius;
  return (tool.radius - tool.corner_radius) * ca * ca / denominator + tool.corner_radius;
}

double flat_stepover(double scallop, double effective_radius) {
  if (std::isinf(effective_radius)) return std::numeric_limits<double>::infinity();
  return 2 * std::sqrt(2 * scallop * effective_radius - scallop * scallop);
}

double curved_stepover(double scallop, double effective_radius, double curvature) {
  if (std::isinf(effective_radius)) return std::numeric_limits<double>::infinity();
  const double R = effective_radius, h = scallop;
  // Tool centres at distance 1/|k| + R (convex) or 1/|k| - R (concave) from the centre of curvature,
  // the scallop's crest at 1/|k| + h or 1/|k| - h; with the angle phi between adjacent contacts,
  // sin^2(phi / 4) = (2 R h - h^2) / (4 |OC| |OP|) and the step along the surface is phi / |k|.
  const double a = 1 - R * curvature, b = 1 - h * curvature;
  if (!(a > 0) || !(b > 0)) return 0;
  const double q = std::sqrt(2 * R * h - h * h) / (2 * std::sqrt(a * b));
  const double k = std::abs(curvature);
  if (k * q < 1e-9) return 4 * q;
  if (k * q >= 1) return 0;
  return 4 * std::asin(k * q) / k;
}

double flat_scallop(double stepover, double effective_radius) {
  if (std::isinf(effective_radius)) return 0;
  if (stepover >= 2 * effective_radius) return effective_radius;  // the traces no longer meet: the tool's whole height stands
  return effective_radius - std::sqrt(effective_radius * effective_radius - stepover * stepover / 4);
}

double level_ground_stepover(const Tool& tool, double scallop) {
  if (tool.kind == ToolKind::ball) return flat_stepover(scallop, tool.radius);
  return 2 * (tool.radius - tool.corner_radius) + flat_stepover(scallop, tool.corner_radius);
}

}  // namespace drom::paths
