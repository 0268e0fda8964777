#include "paths/tool_body.hpp"

#include "support/input_error.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <random>

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

double RevolvedProfile::max_radius() const { return radius.empty() ? 0 : *std::max_element(radius.begin(), radius.end()); }

RevolvedProfile ToolBody::body_profile() const {
  RevolvedProfile p;
  p.z = {flute_length, stick_out};
  p.radius = {shank_radius, shank_radius};
  for (std::size_t k = 0; k < holder.z.size(); ++k) {
    // A step from the shank to the holder's face is a vertical edge: two points at one height.
    p.z.push_back(stick_out + holder.z[k]);
    p.radius.push_back(holder.radius[k]);
  }
  return p;
}

double ToolBody::length() const { return stick_out + (holder.z.empty() ? 0 : holder.z.back()); }

void ToolBody::check() const {
  if (!(cutter.radius > 0) || !(cutter.corner_radius > 0) || cutter.corner_radius > cutter.radius)
    throw InputError("tool: the radius R and corner radius r need 0 < r <= R");
  if (!(shank_radius > 0)) throw InputError("tool: shank_radius must be positive");
  if (!(flute_length >= pivot_height()) || !(stick_out > flute_length))
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

std::vector<SkinPiece> skin_pieces(const ToolBody& tool) {
  const RevolvedProfile p = tool.body_profile();
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

double tool_skin_area(const ToolBody& tool) { return total_area(skin_pieces(tool)); }

std::vector<Eigen::Vector3d> tool_skin_nodes(const ToolBody& tool, int count, double spacing, unsigned seed) {
  const std::vector<SkinPiece> pieces = skin_pieces(tool);
  const double total = total_area(pieces);
  const int n = count > 0 ? count : std::max(1, static_cast<int>(std::lround(total / (spacing * spacing))));
  std::mt19937_64 rng(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<Eigen::Vector3d> nodes;
  nodes.reserve(static_cast<std::size_t>(n));
  const double zc = tool.pivot_height();
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

double cutter_signed_distance(const ToolBody& tool, const Eigen::Vector3d& local) {
  // In the tip frame (height h, radial distance ρ) the cutter is the disc {h = r, ρ ≤ R − r} grown by
  // r (the torus with its flat bottom; a ball when r = R) united with the cylinder ρ ≤ R, r ≤ h ≤ flute.
  const double R = tool.cutter.radius, r = tool.cutter.corner_radius;
  // sqrt, not hypot: lengths in mm neither overflow nor underflow, and the gouge check calls this for
  // every part sample near every pose, where glibc's hypot cost a fifth of the impeller's run.
  const double h = local.z() + tool.pivot_height(), rho = std::sqrt(local.x() * local.x() + local.y() * local.y());
  const double radial = rho - std::clamp(rho, 0.0, R - r), height = h - r;
  const double rounded = std::sqrt(radial * radial + height * height) - r;
  const double dr = rho - R, dz = std::max(r - h, h - tool.flute_length);
  const double out_r = std::max(dr, 0.0), out_z = std::max(dz, 0.0);
  const double cylinder = std::sqrt(out_r * out_r + out_z * out_z) + std::min(std::max(dr, dz), 0.0);
  return std::min(rounded, cylinder);
}

}  // namespace drom::paths
