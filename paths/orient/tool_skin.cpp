#include "paths/orient/tool_skin.hpp"

#include "support/input_error.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

namespace drom::paths {

RevolvedProfile body_profile(const ToolAssembly& tool) {
  RevolvedProfile p;
  p.z = {tool.flutes(), tool.gauge_length};
  p.radius = {tool.shank(), tool.shank()};
  for (std::size_t k = 0; k < tool.holder.z.size(); ++k) {
    // A step from the shank to the holder's face is a vertical edge: two points at one height.
    p.z.push_back(tool.gauge_length + tool.holder.z[k]);
    p.radius.push_back(tool.holder.radius[k]);
  }
  return p;
}

void check_avoidance_tool(const ToolAssembly& tool) {
  const Tool& cutter = tool.cutter;
  const RevolvedProfile& holder = tool.holder;
  if (!(cutter.radius > 0) || !(cutter.corner_radius > 0) || cutter.corner_radius > cutter.radius)
    throw InputError("tool: the radius R and corner radius r need 0 < r <= R");
  if (!(tool.shank_radius > 0)) throw InputError("tool: shank_radius must be positive");
  if (!(tool.flute_length >= cutter.pivot_height()) || !(tool.gauge_length > tool.flute_length))
    throw InputError("tool: need corner radius <= flute_length < stick_out (the shank must show above the flutes)");
  if (holder.z.size() != holder.radius.size()) throw InputError("tool.holder: as many heights as radii");
  for (std::size_t k = 0; k < holder.z.size(); ++k) {
    if (!(holder.radius[k] > 0)) throw InputError("tool.holder: radii must be positive");
    if (k > 0 && holder.z[k] < holder.z[k - 1]) throw InputError("tool.holder: heights must not decrease");
  }
  if (!holder.z.empty() && holder.z.front() != 0) throw InputError("tool.holder: the profile starts at the holder's face (height 0)");
}

namespace {

// Skin pieces: each profile segment is a cone frustum (or an annulus where the height repeats), plus
// the top disc (the flutes' end is inside the cutter: its disc is skipped).
struct SkinPiece {
  double z0, r0, z1, r1, area;
};

std::vector<SkinPiece> skin_pieces(const ToolAssembly& tool) {
  const RevolvedProfile p = body_profile(tool);
  std::vector<SkinPiece> pieces;
  for (std::size_t k = 0; k + 1 < p.z.size(); ++k) {
    const double dz = p.z[k + 1] - p.z[k], dr = p.radius[k + 1] - p.radius[k];
    pieces.push_back({p.z[k], p.radius[k], p.z[k + 1], p.radius[k + 1], std::numbers::pi * (p.radius[k] + p.radius[k + 1]) * std::hypot(dz, dr)});
  }
  pieces.push_back({p.z.back(), p.radius.back(), p.z.back(), 0, std::numbers::pi * p.radius.back() * p.radius.back()});
  return pieces;
}

double total_area(const std::vector<SkinPiece>& pieces) {
  double total = 0;
  for (const auto& q : pieces) total += q.area;
  return total;
}

}  // namespace

double tool_skin_area(const ToolAssembly& tool) { return total_area(skin_pieces(tool)); }

std::vector<Eigen::Vector3d> tool_skin_nodes(const ToolAssembly& tool, int count, double spacing, unsigned seed) {
  const std::vector<SkinPiece> pieces = skin_pieces(tool);
  const double total = total_area(pieces);
  const int n = count > 0 ? count : std::max(1, static_cast<int>(std::lround(total / (spacing * spacing))));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<Eigen::Vector3d> nodes;
  nodes.reserve(static_cast<std::size_t>(n));
  const double zc = tool.cutter.pivot_height();
  for (int i = 0; i < n; ++i) {
    double pick = unit(rng) * total;
    std::size_t k = 0;
    while (k + 1 < pieces.size() && pick > pieces[k].area) pick -= pieces[k++].area;
    const SkinPiece& q = pieces[k];
    // Uniform by area on a frustum: the radius's square is uniform between the ends when the slant
    // is the parameter; sample t with density ∝ r(t).
    double t = unit(rng);
    if (std::abs(q.r1 - q.r0) > 1e-12) {
      const double a = q.r0, b = q.r1;
      t = (std::sqrt(a * a + t * (b * b - a * a)) - a) / (b - a);
    }
    const double r = q.r0 + t * (q.r1 - q.r0), z = q.z0 + t * (q.z1 - q.z0);
    const double phi = 2 * std::numbers::pi * unit(rng);
    nodes.emplace_back(r * std::cos(phi), r * std::sin(phi), z - zc);
  }
  return nodes;
}

double cutter_signed_distance(const ToolAssembly& tool, const Eigen::Vector3d& local) {
  // sqrt, not hypot: lengths in mm neither overflow nor underflow, and the gouge check calls this for
  // every part sample near every pose, where glibc's hypot cost a fifth of the impeller's run.
  const double h = local.z() + tool.cutter.pivot_height(), rho = std::sqrt(local.x() * local.x() + local.y() * local.y());
  return tool.signed_distance(rho, h);
}

}  // namespace drom::paths
