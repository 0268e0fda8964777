#include "paths/cutter/tool_assembly.hpp"

#include "support/input_error.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace drom::paths {

double RevolvedProfile::radius_at(double height) const {
  if (z.empty() || height < z.front() || height > z.back()) return 0;
  const auto it = std::upper_bound(z.begin(), z.end(), height);
  if (it == z.end()) return radius.back();
  const std::size_t k = static_cast<std::size_t>(it - z.begin());
  if (k == 0) return radius.front();
  const double w = z[k] > z[k - 1] ? (height - z[k - 1]) / (z[k] - z[k - 1]) : 1;
  return radius[k - 1] + w * (radius[k] - radius[k - 1]);
}

RevolvedProfile RevolvedProfile::endless_cylinder(double radius) {
  if (!(radius > 0)) return {};
  return cylinder(radius, std::numeric_limits<double>::infinity());
}

double RevolvedProfile::max_radius() const { return radius.empty() ? 0 : *std::max_element(radius.begin(), radius.end()); }

ToolAssembly ToolAssembly::bull_nose(double radius, double corner_radius, double flute_length) {
  if (!(corner_radius > 0 && corner_radius < radius)) throw std::invalid_argument("bull-nose: 0 < corner radius < radius");
  return {Tool::torus(radius, corner_radius), flute_length, 0, 0, {}};
}

double ToolAssembly::reach() const { return std::max({cutter.radius, shank(), has_holder() ? holder_reach() : 0.0}); }

double ToolAssembly::length() const { return gauge_length + (holder.z.empty() ? 0 : holder.z.back()); }

std::string ToolAssembly::name() const {
  std::ostringstream s;
  s << cutter.name() << ", shank D" << 2 * shank();
  if (has_holder()) s << ", holder D" << 2 * holder_reach() << " at " << gauge_length << " mm";
  return s.str();
}

double ToolAssembly::section_radius(double h) const {
  if (h < 0 || h > flutes()) return 0;
  const double r = cutter.corner_radius;
  if (h >= r) return cutter.radius;
  return (cutter.radius - r) + std::sqrt(std::max(0.0, r * r - (r - h) * (r - h)));
}

double ToolAssembly::signed_distance(double rho, double h) const {
  // Rounded box: core [-a, a] x [r, top] dilated by r, then cut by h <= flutes.
  const double r = cutter.corner_radius, a = cutter.radius - cutter.corner_radius, flute = flutes();
  const double top = flute + r;  // the core reaches past the cut so the top stays flat
  const double cx = 0, cy = 0.5 * (r + top);
  const double qx = std::abs(std::abs(rho) - cx) - a;
  const double qy = std::abs(h - cy) - 0.5 * (top - r);
  const double ox = std::max(qx, 0.0), oy = std::max(qy, 0.0);
  const double outside = std::sqrt(ox * ox + oy * oy);  // lengths in mm: no overflow for hypot to guard against
  const double rounded = outside + std::min(std::max(qx, qy), 0.0) - r;
  return std::max(rounded, h - flute);
}

double profile_height(const ToolAssembly& tool, double rho) {
  double h = std::numeric_limits<double>::infinity();
  if (rho <= tool.cutter.radius) h = bottom_height(tool.cutter, rho);
  if (rho <= tool.shank()) h = std::min(h, tool.flutes());
  if (tool.has_holder() && rho <= tool.holder_reach()) h = std::min(h, tool.gauge_length);
  return h;
}

double signed_distance(const ToolAssembly& tool, const ToolPose& pose, const Eigen::Vector3d& x) {
  const Eigen::Vector3d d = x - pose.tip;
  const double h = d.dot(pose.axis);
  return tool.signed_distance((d - h * pose.axis).norm(), h);
}

double swept_signed_distance(const ToolAssembly& tool, const Eigen::Vector3d& axis, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
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

Tool parse_tool(const std::string& text, const std::string& what) {
  std::vector<std::string> parts;
  std::stringstream in(text);
  for (std::string part; std::getline(in, part, ':');) parts.push_back(part);
  const auto number = [&](const std::string& s) {
    double v = 0;
    const auto [end, error] = std::from_chars(s.data(), s.data() + s.size(), v);
    if (error != std::errc() || end != s.data() + s.size() || !(v > 0) || !std::isfinite(v))
      throw InputError(what + " '" + text + "': '" + s + "' is not a positive length in mm");
    return v;
  };
  Tool t;
  if (parts.size() == 2 && (parts[0] == "ball" || parts[0] == "flat")) {
    t.radius = number(parts[1]) / 2;
    t.kind = parts[0] == "ball" ? ToolKind::ball : ToolKind::torus;
    t.corner_radius = parts[0] == "ball" ? t.radius : 0.0;
    return t;
  }
  if (parts.size() == 3 && parts[0] == "torus") {
    t.kind = ToolKind::torus;
    t.radius = number(parts[1]) / 2;
    t.corner_radius = number(parts[2]);
    if (!(t.corner_radius < t.radius)) throw InputError(what + " '" + text + "': the corner radius must be smaller than the tool's radius (a ball is 'ball:D')");
    return t;
  }
  throw InputError(what + " '" + text + "': expected ball:D, flat:D or torus:D:r (diameter D and corner radius r in mm)");
}

}  // namespace drom::paths
