#include "paths/copy/tool_drop.hpp"

#include <algorithm>
#include <cmath>

namespace drom::paths {

namespace {

// p_z - h(rho) for a point at squared distance rho2 <= R^2: the one expression every variant uses,
// so they agree bit for bit.
inline double lifted_height(const Tool& cutter, double rho2, double z) {
  if (cutter.kind == ToolKind::ball) return z - (cutter.radius - std::sqrt(std::max(0.0, cutter.radius * cutter.radius - rho2)));
  const double flat = cutter.radius - cutter.corner_radius;
  if (rho2 <= flat * flat) return z;
  const double d = std::sqrt(rho2) - flat, r = cutter.corner_radius;
  return z - (r - std::sqrt(std::max(0.0, r * r - d * d)));
}

struct Best {
  double value = -std::numeric_limits<double>::infinity();
  int index = -1;
  void offer(double v, int i) {
    if (v > value || (v == value && i < index)) value = v, index = i;
  }
};

Drop finish(const Tool& cutter, double x, double y, const Best& best, const Eigen::Vector3d& p) {
  Drop d;
  if (best.index < 0) return d;
  d.contact = true;
  d.tip = best.value;
  d.point = best.index;
  d.normal = contact_normal(cutter, x, y, d.tip, p);
  return d;
}

}  // namespace

Eigen::Vector3d contact_normal(const Tool& cutter, double x, double y, double tip, const Eigen::Vector3d& p) {
  const double flat = cutter.kind == ToolKind::ball ? 0.0 : cutter.radius - cutter.corner_radius;
  const double tube = cutter.kind == ToolKind::ball ? cutter.radius : cutter.corner_radius;
  const Eigen::Vector2d radial(p.x() - x, p.y() - y);
  const double rho = radial.norm();
  if (tube == 0 || rho <= flat) return Eigen::Vector3d::UnitZ();
  const Eigen::Vector2d centre_xy = Eigen::Vector2d(x, y) + (rho > 0 ? Eigen::Vector2d(radial / rho * flat) : Eigen::Vector2d(Eigen::Vector2d::Zero()));
  const Eigen::Vector3d centre(centre_xy.x(), centre_xy.y(), tip + tube);
  const Eigen::Vector3d n = centre - p;
  const double length = n.norm();
  return length > 0 ? Eigen::Vector3d(n / length) : Eigen::Vector3d(Eigen::Vector3d::UnitZ());
}

Drop drop_brute_force(std::span<const Eigen::Vector3d> points, double x, double y, const Tool& cutter) {
  const double r2 = cutter.radius * cutter.radius;
  Best best;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const double dx = points[i].x() - x, dy = points[i].y() - y, rho2 = dx * dx + dy * dy;
    if (rho2 <= r2) best.offer(lifted_height(cutter, rho2, points[i].z()), static_cast<int>(i));
  }
  return finish(cutter, x, y, best, best.index >= 0 ? points[static_cast<std::size_t>(best.index)] : Eigen::Vector3d::Zero());
}

Drop drop_tool(const geometry::CloudBins& bins, double x, double y, const Tool& cutter) {
  Best best;
  if (bins.empty()) return {};
  const double r = cutter.radius, r2 = r * r;
  const geometry::BinnedPoint* contact = nullptr;
  // Best first down the bins' pyramid: a block's best possible value is its highest point lowered by
  // the profile at the block's nearest distance (h grows with rho). A block that cannot beat (or tie)
  // the best found is not opened; children are opened highest bound first, so the best found rises
  // quickly and most of the disk is never read.
  struct Block {
    double bound;
    int l, i, j;
  };
  const auto bound_of = [&](int l, int i, int j, Block& out) {
    if (i >= bins.level_nx(l) || j >= bins.level_ny(l)) return false;
    const double top = bins.block_top(l, i, j);
    if (top == -std::numeric_limits<double>::infinity()) return false;
    const double d2 = bins.block_distance2(l, i, j, x, y);
    if (d2 > r2) return false;
    out = {top - bottom_height(cutter, std::sqrt(d2)), l, i, j};
    return true;
  };
  const auto beaten = [&](double bound) { return bound < best.value - 1e-12 * (1 + std::abs(best.value)); };
  const auto open = [&](const Block& b, const auto& self) -> void {
    if (beaten(b.bound)) return;
    if (b.l == 0) {
      for (const auto& p : bins.cell_points(b.i, b.j)) {
        const double dx = p.x - x, dy = p.y - y, rho2 = dx * dx + dy * dy;
        if (rho2 > r2) continue;
        const int before = best.index;
        best.offer(lifted_height(cutter, rho2, p.z), p.index);
        if (best.index != before) contact = &p;
      }
      return;
    }
    Block children[4];
    int n = 0;
    for (int c = 0; c < 4; ++c)
      if (bound_of(b.l - 1, 2 * b.i + (c & 1), 2 * b.j + (c >> 1), children[n])) ++n;
    for (int c = 1; c < n; ++c)  // insertion sort, highest bound first (at most four)
      for (int k = c; k > 0 && children[k].bound > children[k - 1].bound; --k) std::swap(children[k], children[k - 1]);
    for (int c = 0; c < n; ++c) self(children[c], self);
  };
  const int l = bins.start_level(r);
  int i0, i1, j0, j1;
  if (!bins.block_range(l, x, y, r, i0, i1, j0, j1)) return {};
  thread_local std::vector<Block> blocks;
  blocks.clear();
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      Block b;
      if (bound_of(l, i, j, b)) blocks.push_back(b);
    }
  std::sort(blocks.begin(), blocks.end(), [](const Block& a, const Block& o) { return a.bound > o.bound; });
  for (const Block& b : blocks) open(b, open);
  return finish(cutter, x, y, best, contact ? Eigen::Vector3d(contact->x, contact->y, contact->z) : Eigen::Vector3d::Zero());
}

Drop drop_tool(const geometry::CloudKdTree& xy_tree, std::span<const Eigen::Vector3d> points, double x, double y, const Tool& cutter,
               std::vector<int>& scratch) {
  // The tree's own distance sums may round otherwise: gather a little wider, test exactly here.
  xy_tree.within(Eigen::Vector3d(x, y, 0), cutter.radius * (1 + 1e-12) + 1e-9, scratch);
  const double r2 = cutter.radius * cutter.radius;
  Best best;
  for (const int i : scratch) {
    const auto& p = points[static_cast<std::size_t>(i)];
    const double dx = p.x() - x, dy = p.y() - y, rho2 = dx * dx + dy * dy;
    if (rho2 <= r2) best.offer(lifted_height(cutter, rho2, p.z()), i);
  }
  return finish(cutter, x, y, best, best.index >= 0 ? points[static_cast<std::size_t>(best.index)] : Eigen::Vector3d::Zero());
}

Drop drop_assembly(const geometry::CloudBins& bins, double x, double y, const ToolAssembly& tool) {
  Drop d = drop_tool(bins, x, y, tool.cutter);
  double floor = -std::numeric_limits<double>::infinity();
  // Only points that would lift the tool above the cutter's own drop matter: the queries read no
  // block lower than that (less a margin for the rounding of the sums, so the result is exact).
  const auto lifting = [&](double height) {
    const double base = std::max(d.tip, floor);
    return base + height - 1e-9 * (1 + (std::isfinite(base) ? std::abs(base) : 0.0) + height);
  };
  if (tool.shank() > tool.cutter.radius) floor = std::max(floor, bins.max_z_within(x, y, tool.shank(), lifting(tool.flutes())) - tool.flutes());
  if (tool.has_holder() && tool.holder_reach() > tool.cutter.radius)
    floor = std::max(floor, bins.max_z_within(x, y, tool.holder_reach(), lifting(tool.gauge_length)) - tool.gauge_length);
  if (floor > d.tip) {
    d.tip = floor;
    d.lifted = true;
  }
  return d;
}

}  // namespace drom::paths
