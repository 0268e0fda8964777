#include "paths/finish/scallop_check.hpp"

#include "geometry/local_geometry.hpp"
#include "paths/finish/parallel_planes.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <unordered_map>

namespace drom::paths {

namespace {

// A straight tool move: the centre disk (radius R - r, normal to the axis) from c0 to c1.
struct Move {
  Eigen::Vector3d c0, c1, axis;
};

// Distance from x to a disk of `radius` centred at c, normal to the unit axis.
double disk_distance(const Eigen::Vector3d& x, const Eigen::Vector3d& c, const Eigen::Vector3d& axis, double radius) {
  const Eigen::Vector3d v = x - c;
  const double along = v.dot(axis);
  const double radial = std::max(0.0, (v - along * axis).norm() - radius);
  return std::sqrt(radial * radial + along * along);
}

// Golden-section minimum of a convex function on [a, b].
template <class F>
double convex_minimum(F f, double a, double b, double* at, int iterations) {
  constexpr double g = 0.6180339887498949;
  double x1 = b - g * (b - a), x2 = a + g * (b - a), f1 = f(x1), f2 = f(x2);
  for (int i = 0; i < iterations; ++i) {
    if (f1 <= f2) {
      b = x2, x2 = x1, f2 = f1, x1 = b - g * (b - a), f1 = f(x1);
    } else {
      a = x1, x1 = x2, f1 = f2, x2 = a + g * (b - a), f2 = f(x2);
    }
  }
  const double fa = f(a), fb = f(b), fm = std::min(f1, f2);
  double best = fm, where = f1 <= f2 ? x1 : x2;
  if (fa < best) best = fa, where = a;
  if (fb < best) best = fb, where = b;
  if (at) *at = where;
  return best;
}

// Distance from x to the disk swept along the move (a convex set, so convex along the move).
double swept_distance(const Eigen::Vector3d& x, const Move& m, double disk_radius) {
  if (disk_radius == 0) {
    // A ball: the distance to the segment of centres.
    const Eigen::Vector3d d = m.c1 - m.c0;
    const double len2 = d.squaredNorm();
    const double s = len2 > 0 ? std::clamp((x - m.c0).dot(d) / len2, 0.0, 1.0) : 0.0;
    return (x - m.c0 - s * d).norm();
  }
  return convex_minimum([&](double s) { return disk_distance(x, m.c0 + s * (m.c1 - m.c0), m.axis, disk_radius); }, 0.0, 1.0, nullptr, 30);
}

}  // namespace

std::vector<double> envelope_heights(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& normals, const std::vector<ToolMove>& tool_moves,
                                     const Tool& tool, double window) {
  const double disk = tool.kind == ToolKind::ball ? 0.0 : tool.radius - tool.corner_radius;
  const double tube = tool.kind == ToolKind::ball ? tool.radius : tool.corner_radius;
  // The moves of the tube's centre disk, and a hash grid over them.
  std::vector<Move> moves;
  moves.reserve(tool_moves.size());
  for (const auto& m : tool_moves) moves.push_back({m.tip0 + tube * m.axis, m.tip1 + tube * m.axis, m.axis});
  std::vector<double> heights(points.size(), std::numeric_limits<double>::quiet_NaN());
  if (moves.empty()) return heights;
  const double cell = std::max(1.0, tool.radius);
  const auto key = [&](const Eigen::Vector3d& p) {
    const auto f = [&](double x) { return static_cast<std::int64_t>(std::floor(x / cell)) & 0x1fffff; };
    return (f(p.x()) << 42) | (f(p.y()) << 21) | f(p.z());
  };
  std::unordered_map<std::int64_t, std::vector<int>> grid;
  const double reach = tool.radius + window;
  for (int k = 0; k < static_cast<int>(moves.size()); ++k) {
    const Eigen::Vector3d lo = moves[static_cast<std::size_t>(k)].c0.cwiseMin(moves[static_cast<std::size_t>(k)].c1) - Eigen::Vector3d::Constant(reach);
    const Eigen::Vector3d hi = moves[static_cast<std::size_t>(k)].c0.cwiseMax(moves[static_cast<std::size_t>(k)].c1) + Eigen::Vector3d::Constant(reach);
    for (double x = std::floor(lo.x() / cell) * cell; x <= hi.x(); x += cell)
      for (double y = std::floor(lo.y() / cell) * cell; y <= hi.y(); y += cell)
        for (double z = std::floor(lo.z() / cell) * cell; z <= hi.z(); z += cell) grid[key(Eigen::Vector3d(x + 0.5 * cell, y + 0.5 * cell, z + 0.5 * cell))].push_back(k);
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    const Eigen::Vector3d& q = points[i];
    const Eigen::Vector3d& n = normals[i];
    const auto found = grid.find(key(q));
    if (found == grid.end()) continue;
    double entry = std::numeric_limits<double>::infinity();
    for (const int k : found->second) {
      const Move& m = moves[static_cast<std::size_t>(k)];
      const auto f = [&](double t) { return swept_distance(q + t * n, m, disk) - tube; };
      if (f(0) > window) continue;  // the distance changes at most as fast as t
      const double lo = -window;
      if (f(lo) <= 0) {
        entry = std::min(entry, lo);
        continue;
      }
      double at = 0;
      if (convex_minimum(f, lo, std::min(window, entry), &at, 40) > 0) continue;
      double a0 = lo, a1 = at;  // f(a0) > 0 >= f(a1)
      for (int it = 0; it < 36; ++it) {
        const double mid = 0.5 * (a0 + a1);
        (f(mid) > 0 ? a0 : a1) = mid;
      }
      entry = std::min(entry, a1);
    }
    if (std::isfinite(entry)) heights[i] = entry;
  }
  return heights;
}

ScallopCheck check_scallop(const geometry::NurbsSurface& surface, const std::vector<ZoneMachining>& zones, const Tool& tool, double u0, double u1, double v0,
                           double v1, int count_u, int count_v, double window) {
  // Tool moves in the part's frame.
  std::vector<ToolMove> moves;
  Eigen::Vector3d side = Eigen::Vector3d::Zero();
  for (const auto& z : zones) {
    const Eigen::Vector3d axis = z.setup.axis();
    for (const auto& p : z.passes) {
      for (std::size_t i = 0; i + 1 < p.cc.size(); ++i)
        moves.push_back({cutter_location(p.cc[i], p.normals[i], tool, axis), cutter_location(p.cc[i + 1], p.normals[i + 1], tool, axis), axis});
      for (const auto& n : p.normals) side += n;
    }
  }
  std::vector<Eigen::Vector3d> points, normals;
  std::vector<Eigen::Vector2d> uv;
  for (int a = 0; a < count_u; ++a)
    for (int b = 0; b < count_v; ++b) {
      const double u = count_u > 1 ? u0 + (u1 - u0) * a / (count_u - 1) : u0, v = count_v > 1 ? v0 + (v1 - v0) * b / (count_v - 1) : v0;
      const auto g = geometry::local_geometry(surface.derivatives(surface.u_min() + u * (surface.u_max() - surface.u_min()),
                                                                   surface.v_min() + v * (surface.v_max() - surface.v_min())));
      points.push_back(g.point);
      normals.push_back(g.normal.dot(side) < 0 ? Eigen::Vector3d(-g.normal) : g.normal);
      uv.emplace_back(u, v);
    }
  ScallopCheck out;
  out.heights = envelope_heights(points, normals, moves, tool, window);
  for (std::size_t i = 0; i < out.heights.size(); ++i) {
    const double entry = out.heights[i];
    if (!std::isfinite(entry)) continue;
    ++out.points;
    if (entry > out.max_height) {
      out.max_height = entry;
      out.worst_uv = uv[i];
    }
    out.max_gouge = std::max(out.max_gouge, -entry);
  }
  return out;
}

}  // namespace drom::paths
