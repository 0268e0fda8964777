#include "paths/copy/cloud_roughing.hpp"

#include "geometry/cloud_bins.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <stdexcept>

namespace drom::paths {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// Distance from p to the box (0 inside).
double box_distance(const geometry::Box3& box, const Eigen::Vector3d& p) {
  const Eigen::Vector3d d = (box.lo - p).cwiseMax(p - box.hi).cwiseMax(Eigen::Vector3d::Zero());
  return d.norm();
}

}  // namespace

double roughing_voxel(const CloudRoughingSettings& s) { return s.voxel > 0 ? s.voxel : std::min({s.longitudinal_step, s.transverse_step, s.depth}) / 4; }

CloudRoughing plan_cloud_roughing(const geometry::CloudVoxelMap& map, const Eigen::Matrix3d& q, const geometry::Box3& stock, const CloudArea& area, double bottom,
                                  const CloudRoughingSettings& s) {
  const Tool& cutter = s.tool.cutter;
  if (!(cutter.radius > 0) || !(s.longitudinal_step > 0) || !(s.transverse_step > 0) || !(s.depth > 0) || !(s.allowance >= 0))
    throw std::invalid_argument("cloud roughing: the tool radius, steps and depth must be positive, the allowance not negative");
  if (!(s.ramp_angle > 0 && s.ramp_angle < 90)) throw std::invalid_argument("cloud roughing: the ramp angle must lie in (0, 90) degrees");
  if (stock.empty()) throw std::invalid_argument("cloud roughing: no stock");
  CloudRoughing out;
  out.voxel = map.edge();
  const auto voxels = map.voxels();
  out.voxels = voxels.size();
  std::vector<Eigen::Vector3d> barycentres;
  barycentres.reserve(voxels.size());
  for (const auto& v : voxels) barycentres.push_back(q * v.barycentre);
  const geometry::CloudBins bins(barycentres, std::max(cutter.radius / 2, map.edge()));
  // A barycentre stands for its voxel's points (within the diagonal) and for the tool's move to the
  // next node (within half a step): both widen the tool.
  const double diagonal = map.edge() * std::sqrt(3.0);
  const double half_step = 0.5 * s.longitudinal_step;  // moves along a pass; links across are checked on their own
  out.inflation = diagonal + half_step;
  // The height every node must keep above: the barycentres' highest within the widened tool, plus the
  // allowance and the diagonal (the axial part of the same two).
  const auto floor_at = [&](double x, double y, double widen) {
    double h = bins.max_z_within(x, y, std::max(cutter.radius, s.tool.shank()) + s.allowance + diagonal + widen);
    if (s.tool.has_holder()) h = std::max(h, bins.max_z_within(x, y, s.tool.holder_reach() + s.allowance + diagonal + widen) - s.tool.gauge_length);
    return h + s.allowance + diagonal;
  };

  // The stock in the drop frame: its top, and whether a point stands within a tool radius of it.
  double top = -kInfinity;
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner((c & 1) ? stock.hi.x() : stock.lo.x(), (c & 2) ? stock.hi.y() : stock.lo.y(), (c & 4) ? stock.hi.z() : stock.lo.z());
    top = std::max(top, (q * corner).z());
  }
  const auto in_stock = [&](double x, double y, double z) { return box_distance(stock, q.transpose() * Eigen::Vector3d(x, y, z)) <= cutter.radius; };

  // The node grid and each node's floor.
  if (area.empty()) return out;
  const int nx = static_cast<int>(std::ceil((area.x_max() - area.x_min()) / s.longitudinal_step)) + 1;
  const int ny = static_cast<int>(std::ceil((area.y_max() - area.y_min()) / s.transverse_step)) + 1;
  const auto X = [&](int i) { return area.x_min() + i * s.longitudinal_step; };
  const auto Y = [&](int j) { return area.y_min() + j * s.transverse_step; };
  const auto id = [&](int i, int j) { return static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(i); };
  std::vector<double> floor(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny), kInfinity);
  std::vector<char> inside(floor.size(), 0);
  tbb::parallel_for(0, ny, [&](int j) {
    for (int i = 0; i < nx; ++i) {
      inside[id(i, j)] = area.contains(X(i), Y(j));
      if (inside[id(i, j)]) floor[id(i, j)] = floor_at(X(i), Y(j), half_step);
    }
  });

  // Layers from the stock's top down to `bottom`.
  std::vector<double> levels;
  for (double z = top - s.depth; z >= bottom - 1e-9; z -= s.depth) levels.push_back(z);
  if (levels.empty() || levels.back() > bottom + 1e-9) levels.push_back(std::max(bottom, top - s.depth * static_cast<double>(levels.size() + 1)));
  if (levels.back() >= top) levels.pop_back();
  out.layers = static_cast<int>(levels.size());
  if (levels.empty()) return out;
  out.top = levels.front(), out.bottom = levels.back();

  const double tan_ramp = std::tan(s.ramp_angle * std::numbers::pi / 180);
  const double traverse = top + s.clearance;
  // Per node, the height down to which its column is open (air): the stock's top where the stock
  // stands there at some layer, -infinity elsewhere; lowered as the layers cut it (the flutes clear
  // everything from the cut up to their length).
  std::vector<double> open_to(floor.size(), -kInfinity);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if (!inside[id(i, j)]) continue;
      for (const double z : levels)
        if (in_stock(X(i), Y(j), z)) open_to[id(i, j)] = std::max(open_to[id(i, j)], std::min(top, z + s.depth));
    }
  const auto node_near = [&](double x, double y) -> std::size_t {
    const int i = std::clamp(static_cast<int>(std::lround((x - area.x_min()) / s.longitudinal_step)), 0, nx - 1);
    const int j = std::clamp(static_cast<int>(std::lround((y - area.y_min()) / s.transverse_step)), 0, ny - 1);
    return id(i, j);
  };
  // Whether the tool at height z over (x, y) clears the cloud (`widen`: the distance to the nearest
  // position actually tested), and descends there through open space.
  const auto clear_at = [&](double x, double y, double z, double widen) { return z >= floor_at(x, y, widen); };
  const double fine = std::max(0.05, s.longitudinal_step / 4);
  // `open_level`: the column over every sample must be open down to it (-infinity: not asked).
  const auto line_is_clear = [&](const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, double open_level) {
    const int samples = std::max(1, static_cast<int>(std::ceil((p1 - p0).head<2>().norm() / fine)));
    for (int t = 0; t <= samples; ++t) {
      const Eigen::Vector3d p = p0 + (p1 - p0) * (static_cast<double>(t) / samples);
      if (!clear_at(p.x(), p.y(), p.z(), 0.5 * fine)) return false;
      if (open_to[node_near(p.x(), p.y())] > open_level + 1e-9) return false;
    }
    return true;
  };

  CloudPath& path = out.path;
  path.add({X(0), Y(0), traverse}, Motion::rapid);
  bool down = false;  // the tool is at the layer's level, at the end of the last segment
  const auto retract = [&] {
    if (!down) return;
    const Eigen::Vector3d at = path.tips.back();
    path.add({at.x(), at.y(), traverse}, Motion::rapid);
    down = false;
    ++out.retracts;
  };
  for (std::size_t layer = 0; layer < levels.size(); ++layer) {
    const double z = levels[layer], above = layer == 0 ? top : levels[layer - 1];
    std::vector<std::size_t> cut_here;
    for (int j = 0; j < ny; ++j) {
      const bool reverse = j % 2 == 1;
      const auto node_at = [&](int k) { return reverse ? nx - 1 - k : k; };  // travel order
      std::vector<char> stock_here(static_cast<std::size_t>(nx)), free_here(static_cast<std::size_t>(nx));
      for (int k = 0; k < nx; ++k) {
        const int i = node_at(k);
        stock_here[static_cast<std::size_t>(k)] = inside[id(i, j)] && in_stock(X(i), Y(j), z);
        free_here[static_cast<std::size_t>(k)] = stock_here[static_cast<std::size_t>(k)] && z >= floor[id(i, j)];
        if (stock_here[static_cast<std::size_t>(k)]) {
          ++out.nodes;
          if (!free_here[static_cast<std::size_t>(k)]) ++out.blocked;
        }
      }
      for (int k = 0; k < nx;) {
        if (!free_here[static_cast<std::size_t>(k)]) {
          ++k;
          continue;
        }
        int e = k;
        while (e + 1 < nx && free_here[static_cast<std::size_t>(e + 1)]) ++e;
        ++out.segments;
        const Eigen::Vector3d a(X(node_at(k)), Y(j), z), b(X(node_at(e)), Y(j), z);
        const double length = (b - a).norm();
        const Eigen::Vector3d forward(reverse ? -1 : 1, 0, 0);
        // Joined to the last segment at the layer's level when it ends next to this one's start and
        // the straight move clears the cloud (the zigzag of a layer): no entry needed.
        const Eigen::Vector3d at = path.tips.back();
        if (down && std::abs(at.z() - z) < 1e-9 && (a - at).head<2>().norm() <= 1.5 * std::max(s.longitudinal_step, s.transverse_step) + 1e-9 &&
            line_is_clear(at, a, kInfinity)) {
          ++out.links;
          path.add(a, Motion::link, static_cast<int>(layer));
          for (int t = k + 1; t <= e; ++t) path.add({X(node_at(t)), Y(j), z}, Motion::cut, static_cast<int>(layer));
          for (int t = k; t <= e; ++t) cut_here.push_back(id(node_at(t), j));
          out.cut += e - k + 1;
          k = e + 1;
          continue;
        }
        // Entry: from the side, where the node before lies outside the stock and open down to the layer.
        std::vector<Eigen::Vector3d> entry;  // the first point is reached from above
        const Eigen::Vector3d outside = a - forward * s.longitudinal_step;
        const bool outside_open = std::none_of(levels.begin(), levels.begin() + static_cast<std::ptrdiff_t>(layer) + 1, [&](double l) { return in_stock(outside.x(), outside.y(), l); }) &&
                                  !in_stock(outside.x(), outside.y(), top);
        if (outside_open && line_is_clear(outside, a, kInfinity) &&
            clear_at(outside.x(), outside.y(), z, 0.5 * fine)) {
          entry = {outside, a};
          ++out.side_entries;
        } else {
          // A ramp down from the layer above: straight along the segment, or zigzag within it.
          const double run = (above - z) / tan_ramp, leg = std::min(run, length);
          bool ok = leg >= std::max(s.longitudinal_step, 1.0) - 1e-9;  // a leg of one node step at least
          std::vector<Eigen::Vector3d> ramp;
          if (ok) {
            ramp.push_back({a.x(), a.y(), above});
            double travelled = 0;
            for (int l = 0; travelled < run - 1e-9; ++l) {
              const double step = std::min(leg, run - travelled);
              const Eigen::Vector3d from = ramp.back(), direction = l % 2 == 0 ? forward : Eigen::Vector3d(-forward);
              travelled += step;
              ramp.push_back({from.x() + direction.x() * step, from.y(), above - travelled * tan_ramp});
            }
            ramp.back().z() = z;
            for (std::size_t r = 1; r < ramp.size() && ok; ++r) ok = line_is_clear(ramp[r - 1], ramp[r], above);
            ok = ok && open_to[node_near(a.x(), a.y())] <= above + 1e-9;
            if (ok && (ramp.back() - a).norm() > 1e-9) ramp.push_back(a);  // back to cut what the ramp skipped
          }
          if (!ok) {
            ++out.skipped_segments;
            out.unreachable += e - k + 1;
            k = e + 1;
            continue;
          }
          (ramp.size() > 3 ? out.zigzag_ramps : out.ramps) += 1;
          entry = ramp;
        }
        // Retract, traverse, descend to the entry's first point (down an open column), enter.
        const Eigen::Vector3d start = entry.front();
        retract();
        path.add({start.x(), start.y(), traverse}, Motion::rapid);
        path.add({start.x(), start.y(), std::min(traverse, start.z() + s.clearance)}, Motion::rapid);
        path.add(start, Motion::cut, static_cast<int>(layer));
        for (std::size_t r = 1; r < entry.size(); ++r) path.add(entry[r], Motion::cut, static_cast<int>(layer));
        for (int t = k + 1; t <= e; ++t) path.add({X(node_at(t)), Y(j), z}, Motion::cut, static_cast<int>(layer));
        for (int t = k; t <= e; ++t) cut_here.push_back(id(node_at(t), j));
        out.cut += e - k + 1;
        down = true;
        k = e + 1;
      }
    }
    // The flutes clear each cut node's column from the layer up.
    for (const std::size_t n : cut_here)
      if (open_to[n] <= z + s.tool.flutes() + 1e-9) open_to[n] = z;
  }
  retract();
  return out;
}

}  // namespace drom::paths
