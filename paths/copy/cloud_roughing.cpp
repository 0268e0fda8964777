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

// The planner's stages over one packet: the node grid and each node's floor, the layers, the columns
// the stock leaves open, then layer by layer the segments of free nodes, each entered from the side or
// by a checked ramp, joined or retracted between. Its state is the path as it grows.
class CloudRoughingPlanner {
 public:
  CloudRoughingPlanner(const geometry::CloudVoxelMap& map, const Eigen::Matrix3d& q, const geometry::Box3& stock, const CloudArea& area,
                       const CloudRoughingSettings& s, CloudRoughing& out);
  void grid_nodes();
  bool place_layers(double bottom);  // false: no layer between the stock's top and the bottom
  void open_columns();
  void cut_layer(std::size_t layer);
  void retract();

 private:
  double X(int i) const { return area_.x_min() + i * s_.longitudinal_step; }
  double Y(int j) const { return area_.y_min() + j * s_.transverse_step; }
  std::size_t id(int i, int j) const { return static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i); }
  // The height every node must keep above: the barycentres' highest within the widened tool, plus the
  // allowance and the diagonal (the axial part of the same two).
  double floor_at(double x, double y, double widen) const {
    double h = bins_.max_z_within(x, y, std::max(cutter_.radius, s_.tool.shank()) + s_.allowance + diagonal_ + widen);
    if (s_.tool.has_holder()) h = std::max(h, bins_.max_z_within(x, y, s_.tool.holder_reach() + s_.allowance + diagonal_ + widen) - s_.tool.gauge_length);
    return h + s_.allowance + diagonal_;
  }
  // Whether a point stands within a tool radius of the stock (drop frame).
  bool in_stock(double x, double y, double z) const { return box_distance(stock_, q_.transpose() * Eigen::Vector3d(x, y, z)) <= cutter_.radius; }
  std::size_t node_near(double x, double y) const {
    const int i = std::clamp(static_cast<int>(std::lround((x - area_.x_min()) / s_.longitudinal_step)), 0, nx_ - 1);
    const int j = std::clamp(static_cast<int>(std::lround((y - area_.y_min()) / s_.transverse_step)), 0, ny_ - 1);
    return id(i, j);
  }
  // Whether the tool at height z over (x, y) clears the cloud (`widen`: the distance to the nearest
  // position actually tested).
  bool clear_at(double x, double y, double z, double widen) const { return z >= floor_at(x, y, widen); }
  bool line_is_clear(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, double open_level) const;
  bool side_is_open(const Eigen::Vector3d& outside, std::size_t layer) const;
  std::vector<Eigen::Vector3d> ramp_into(const Eigen::Vector3d& a, const Eigen::Vector3d& forward, double length, double z, double above) const;
  void cut_segment(std::size_t layer, int j, int k, int e, std::vector<std::size_t>& cut_here);

  const Eigen::Matrix3d& q_;
  const geometry::Box3& stock_;
  const CloudArea& area_;
  const CloudRoughingSettings& s_;
  CloudRoughing& out_;
  const Tool& cutter_;
  std::vector<Eigen::Vector3d> barycentres_;  // the map's voxels', drop frame
  geometry::CloudBins bins_;
  double diagonal_ = 0, half_step_ = 0, top_ = -kInfinity, tan_ramp_ = 0, traverse_ = 0, fine_ = 0;
  int nx_ = 0, ny_ = 0;
  std::vector<double> floor_, open_to_, levels_;
  std::vector<char> inside_;
  bool down_ = false;  // the tool is at the layer's level, at the end of the last segment
};

std::vector<Eigen::Vector3d> barycentres_in(const geometry::CloudVoxelMap& map, const Eigen::Matrix3d& q) {
  const auto voxels = map.voxels();
  std::vector<Eigen::Vector3d> barycentres;
  barycentres.reserve(voxels.size());
  for (const auto& v : voxels) barycentres.push_back(q * v.barycentre);
  return barycentres;
}

CloudRoughingPlanner::CloudRoughingPlanner(const geometry::CloudVoxelMap& map, const Eigen::Matrix3d& q, const geometry::Box3& stock, const CloudArea& area,
                                           const CloudRoughingSettings& s, CloudRoughing& out)
    : q_(q), stock_(stock), area_(area), s_(s), out_(out), cutter_(s.tool.cutter), barycentres_(barycentres_in(map, q)),
      bins_(barycentres_, std::max(s.tool.cutter.radius / 2, map.edge())) {
  out.voxel = map.edge();
  out.voxels = barycentres_.size();
  // A barycentre stands for its voxel's points (within the diagonal) and for the tool's move to the
  // next node (within half a step): both widen the tool.
  diagonal_ = map.edge() * std::sqrt(3.0);
  half_step_ = 0.5 * s.longitudinal_step;  // moves along a pass; links across are checked on their own
  out.inflation = diagonal_ + half_step_;
  // The stock's top in the drop frame.
  for (int c = 0; c < 8; ++c) {
    const Eigen::Vector3d corner((c & 1) ? stock.hi.x() : stock.lo.x(), (c & 2) ? stock.hi.y() : stock.lo.y(), (c & 4) ? stock.hi.z() : stock.lo.z());
    top_ = std::max(top_, (q * corner).z());
  }
  tan_ramp_ = std::tan(s.ramp_angle * std::numbers::pi / 180);
  traverse_ = top_ + s.clearance;
  fine_ = std::max(0.05, s.longitudinal_step / 4);
}

// Stage 1: the node grid and each node's floor.
void CloudRoughingPlanner::grid_nodes() {
  nx_ = static_cast<int>(std::ceil((area_.x_max() - area_.x_min()) / s_.longitudinal_step)) + 1;
  ny_ = static_cast<int>(std::ceil((area_.y_max() - area_.y_min()) / s_.transverse_step)) + 1;
  floor_.assign(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_), kInfinity);
  inside_.assign(floor_.size(), 0);
  tbb::parallel_for(0, ny_, [&](int j) {
    for (int i = 0; i < nx_; ++i) {
      inside_[id(i, j)] = area_.contains(X(i), Y(j));
      if (inside_[id(i, j)]) floor_[id(i, j)] = floor_at(X(i), Y(j), half_step_);
    }
  });
}

// Stage 2: layers from the stock's top down to `bottom`.
bool CloudRoughingPlanner::place_layers(double bottom) {
  std::vector<double>& levels = levels_;
  for (double z = top_ - s_.depth; z >= bottom - 1e-9; z -= s_.depth) levels.push_back(z);
  if (levels.empty() || levels.back() > bottom + 1e-9) levels.push_back(std::max(bottom, top_ - s_.depth * static_cast<double>(levels.size() + 1)));
  if (levels.back() >= top_) levels.pop_back();
  out_.layers = static_cast<int>(levels.size());
  if (levels.empty()) return false;
  out_.top = levels.front(), out_.bottom = levels.back();
  return true;
}

// Stage 3: per node, the height down to which its column is open (air): the stock's top where the
// stock stands there at some layer, -infinity elsewhere; lowered as the layers cut it (the flutes
// clear everything from the cut up to their length).
void CloudRoughingPlanner::open_columns() {
  open_to_.assign(floor_.size(), -kInfinity);
  for (int j = 0; j < ny_; ++j)
    for (int i = 0; i < nx_; ++i) {
      if (!inside_[id(i, j)]) continue;
      for (const double z : levels_)
        if (in_stock(X(i), Y(j), z)) open_to_[id(i, j)] = std::max(open_to_[id(i, j)], std::min(top_, z + s_.depth));
    }
  out_.path.add({X(0), Y(0), traverse_}, Motion::rapid);
}

// `open_level`: the column over every sample must be open down to it (-infinity: not asked).
bool CloudRoughingPlanner::line_is_clear(const Eigen::Vector3d& p0, const Eigen::Vector3d& p1, double open_level) const {
  const int samples = std::max(1, static_cast<int>(std::ceil((p1 - p0).head<2>().norm() / fine_)));
  for (int t = 0; t <= samples; ++t) {
    const Eigen::Vector3d p = p0 + (p1 - p0) * (static_cast<double>(t) / samples);
    if (!clear_at(p.x(), p.y(), p.z(), 0.5 * fine_)) return false;
    if (open_to_[node_near(p.x(), p.y())] > open_level + 1e-9) return false;
  }
  return true;
}

// A side entry: the node before the segment lies outside the stock at every layer so far and at the top.
bool CloudRoughingPlanner::side_is_open(const Eigen::Vector3d& outside, std::size_t layer) const {
  return std::none_of(levels_.begin(), levels_.begin() + static_cast<std::ptrdiff_t>(layer) + 1, [&](double l) { return in_stock(outside.x(), outside.y(), l); }) &&
         !in_stock(outside.x(), outside.y(), top_);
}

// A ramp down from the layer above: straight along the segment, or zigzag within it; every leg checked
// against the cloud and against the material the layer above left. Empty: no safe ramp.
std::vector<Eigen::Vector3d> CloudRoughingPlanner::ramp_into(const Eigen::Vector3d& a, const Eigen::Vector3d& forward, double length, double z, double above) const {
  const double run = (above - z) / tan_ramp_, leg = std::min(run, length);
  bool ok = leg >= std::max(s_.longitudinal_step, 1.0) - 1e-9;  // a leg of one node step at least
  std::vector<Eigen::Vector3d> ramp;
  if (ok) {
    ramp.push_back({a.x(), a.y(), above});
    double travelled = 0;
    for (int l = 0; travelled < run - 1e-9; ++l) {
      const double step = std::min(leg, run - travelled);
      const Eigen::Vector3d from = ramp.back(), direction = l % 2 == 0 ? forward : Eigen::Vector3d(-forward);
      travelled += step;
      ramp.push_back({from.x() + direction.x() * step, from.y(), above - travelled * tan_ramp_});
    }
    ramp.back().z() = z;
    for (std::size_t r = 1; r < ramp.size() && ok; ++r) ok = line_is_clear(ramp[r - 1], ramp[r], above);
    ok = ok && open_to_[node_near(a.x(), a.y())] <= above + 1e-9;
    if (ok && (ramp.back() - a).norm() > 1e-9) ramp.push_back(a);  // back to cut what the ramp skipped
  }
  if (!ok) ramp.clear();
  return ramp;
}

void CloudRoughingPlanner::retract() {
  if (!down_) return;
  const Eigen::Vector3d at = out_.path.tips.back();
  out_.path.add({at.x(), at.y(), traverse_}, Motion::rapid);
  down_ = false;
  ++out_.retracts;
}

// One segment of free nodes k..e (in travel order) of pass j: joined to the last one at the layer's
// level when it ends next to this one's start and the straight move clears the cloud (the zigzag of a
// layer); else entered from the side or by a ramp after a retract; left, and counted, when neither is
// safe.
void CloudRoughingPlanner::cut_segment(std::size_t layer, int j, int k, int e, std::vector<std::size_t>& cut_here) {
  CloudPath& path = out_.path;
  const double z = levels_[layer], above = layer == 0 ? top_ : levels_[layer - 1];
  const bool reverse = j % 2 == 1;
  const auto node_at = [&](int t) { return reverse ? nx_ - 1 - t : t; };  // travel order
  ++out_.segments;
  const Eigen::Vector3d a(X(node_at(k)), Y(j), z), b(X(node_at(e)), Y(j), z);
  const double length = (b - a).norm();
  const Eigen::Vector3d forward(reverse ? -1 : 1, 0, 0);
  const Eigen::Vector3d at = path.tips.back();
  const bool joined = down_ && std::abs(at.z() - z) < 1e-9 && (a - at).head<2>().norm() <= 1.5 * std::max(s_.longitudinal_step, s_.transverse_step) + 1e-9 &&
                      line_is_clear(at, a, kInfinity);
  if (joined) {
    ++out_.links;
    path.add(a, Motion::link, static_cast<int>(layer));
  } else {
    std::vector<Eigen::Vector3d> entry;  // the first point is reached from above
    const Eigen::Vector3d outside = a - forward * s_.longitudinal_step;
    if (side_is_open(outside, layer) && line_is_clear(outside, a, kInfinity) && clear_at(outside.x(), outside.y(), z, 0.5 * fine_)) {
      entry = {outside, a};
      ++out_.side_entries;
    } else {
      entry = ramp_into(a, forward, length, z, above);
      if (entry.empty()) {
        ++out_.skipped_segments;
        out_.unreachable += e - k + 1;
        return;
      }
      (entry.size() > 3 ? out_.zigzag_ramps : out_.ramps) += 1;
    }
    // Retract, traverse, descend to the entry's first point (down an open column), enter.
    const Eigen::Vector3d start = entry.front();
    retract();
    path.add({start.x(), start.y(), traverse_}, Motion::rapid);
    path.add({start.x(), start.y(), std::min(traverse_, start.z() + s_.clearance)}, Motion::rapid);
    path.add(start, Motion::cut, static_cast<int>(layer));
    for (std::size_t r = 1; r < entry.size(); ++r) path.add(entry[r], Motion::cut, static_cast<int>(layer));
  }
  for (int t = k + 1; t <= e; ++t) path.add({X(node_at(t)), Y(j), z}, Motion::cut, static_cast<int>(layer));
  for (int t = k; t <= e; ++t) cut_here.push_back(id(node_at(t), j));
  out_.cut += e - k + 1;
  if (!joined) down_ = true;
}

// Stage 4, one layer: each pass's nodes inside the stock counted, its free runs cut as segments; the
// flutes then clear each cut node's column from the layer up.
void CloudRoughingPlanner::cut_layer(std::size_t layer) {
  const double z = levels_[layer];
  std::vector<std::size_t> cut_here;
  for (int j = 0; j < ny_; ++j) {
    const bool reverse = j % 2 == 1;
    std::vector<char> free_here(static_cast<std::size_t>(nx_));
    for (int k = 0; k < nx_; ++k) {
      const int i = reverse ? nx_ - 1 - k : k;
      const bool stock_here = inside_[id(i, j)] && in_stock(X(i), Y(j), z);
      free_here[static_cast<std::size_t>(k)] = stock_here && z >= floor_[id(i, j)];
      if (stock_here) {
        ++out_.nodes;
        if (!free_here[static_cast<std::size_t>(k)]) ++out_.blocked;
      }
    }
    for (int k = 0; k < nx_;) {
      if (!free_here[static_cast<std::size_t>(k)]) {
        ++k;
        continue;
      }
      int e = k;
      while (e + 1 < nx_ && free_here[static_cast<std::size_t>(e + 1)]) ++e;
      cut_segment(layer, j, k, e, cut_here);
      k = e + 1;
    }
  }
  for (const std::size_t n : cut_here)
    if (open_to_[n] <= z + s_.tool.flutes() + 1e-9) open_to_[n] = z;
}

}  // namespace

double roughing_voxel(const CloudRoughingSettings& s) { return s.voxel > 0 ? s.voxel : std::min({s.longitudinal_step, s.transverse_step, s.depth}) / 4; }

CloudRoughing plan_cloud_roughing(const geometry::CloudVoxelMap& map, const Eigen::Matrix3d& q, const geometry::Box3& stock, const CloudArea& area, double bottom,
                                  const CloudRoughingSettings& s) {
  if (!(s.tool.cutter.radius > 0) || !(s.longitudinal_step > 0) || !(s.transverse_step > 0) || !(s.depth > 0) || !(s.allowance >= 0))
    throw std::invalid_argument("cloud roughing: the tool radius, steps and depth must be positive, the allowance not negative");
  if (!(s.ramp_angle > 0 && s.ramp_angle < 90)) throw std::invalid_argument("cloud roughing: the ramp angle must lie in (0, 90) degrees");
  if (stock.empty()) throw std::invalid_argument("cloud roughing: no stock");
  CloudRoughing out;
  CloudRoughingPlanner planner(map, q, stock, area, s, out);
  if (area.empty()) return out;
  planner.grid_nodes();
  if (!planner.place_layers(bottom)) return out;
  planner.open_columns();
  for (std::size_t layer = 0; layer < static_cast<std::size_t>(out.layers); ++layer) planner.cut_layer(layer);
  planner.retract();
  return out;
}

}  // namespace drom::paths
