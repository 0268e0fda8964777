#include "paths/tool_assembly.hpp"

#include "support/input_error.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <limits>
#include <sstream>
#include <vector>

namespace drom::paths {

bool is_flat(const Tool& cutter) { return cutter.kind == ToolKind::torus && cutter.corner_radius == 0; }

double ToolAssembly::reach() const { return std::max({cutter.radius, shank(), has_holder() ? holder_radius : 0.0}); }

std::string ToolAssembly::name() const {
  std::ostringstream s;
  s << cutter.name() << ", shank D" << 2 * shank();
  if (has_holder()) s << ", holder D" << 2 * holder_radius << " at " << gauge_length << " mm";
  return s.str();
}

double cutter_height(const Tool& cutter, double rho) {
  if (cutter.kind == ToolKind::ball) return cutter.radius - std::sqrt(std::max(0.0, cutter.radius * cutter.radius - rho * rho));
  const double flat = cutter.radius - cutter.corner_radius;
  if (rho <= flat) return 0;
  const double d = rho - flat, r = cutter.corner_radius;
  return r - std::sqrt(std::max(0.0, r * r - d * d));
}

double profile_height(const ToolAssembly& tool, double rho) {
  double h = std::numeric_limits<double>::infinity();
  if (rho <= tool.cutter.radius) h = cutter_height(tool.cutter, rho);
  if (rho <= tool.shank()) h = std::min(h, tool.flutes());
  if (tool.has_holder() && rho <= tool.holder_radius) h = std::min(h, tool.gauge_length);
  return h;
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
