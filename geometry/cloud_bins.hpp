#pragma once
// A 2D bin grid of a cloud in a drop frame (Z the tool axis): the points sorted by the square cell of
// their XY (a counting sort, O(N)), each cell's highest point, and a pyramid of those maxima over
// 2x2, 4x4, ... cells. Every query a tool makes of a cloud is "what stands within r of this axis":
// the drop (what lies under the tool), and the shank's and the holder's clearance (is anything above
// this height within this radius). The maxima let a query skip every cell that cannot matter, so a
// large radius (a 53 mm holder) costs little more than a small one.
#include <Eigen/Core>

#include <limits>
#include <span>
#include <vector>

namespace drom::geometry {

struct BinnedPoint {
  double x = 0, y = 0, z = 0;
  int index = 0;  // in the cloud the bins were built from
};

class CloudBins {
 public:
  CloudBins() = default;
  // `cell` (mm) is a speed knob only: results do not depend on it. It is enlarged where the cloud's
  // extent would need more than about 16 million cells.
  CloudBins(std::span<const Eigen::Vector3d> points, double cell);

  bool empty() const { return points_.empty(); }
  std::size_t size() const { return points_.size(); }
  double cell() const { return cell_; }
  int nx() const { return nx_; }
  int ny() const { return ny_; }
  // The cells overlapping the square [x - r, x + r] x [y - r, y + r], clamped to the grid; false when
  // the square misses the grid.
  bool cell_range(double x, double y, double r, int& i0, int& i1, int& j0, int& j1) const;
  std::span<const BinnedPoint> cell_points(int i, int j) const {
    const std::size_t c = cell_id(i, j);
    return {points_.data() + start_[c], points_.data() + start_[c + 1]};
  }
  double cell_max_z(int i, int j) const { return levels_.front()[cell_id(i, j)]; }
  // Squared distance from (x, y) to cell (i, j)'s rectangle (0 inside it).
  double cell_distance2(int i, int j, double x, double y) const;

  // The highest z of the points within r of (x, y) in XY (distance <= r), or -infinity when none.
  // With `above`: the larger of that and `above`, and no block whose maximum is not above it is read
  // (for a caller that only cares about points higher than something it already has).
  double max_z_within(double x, double y, double r, double above = -std::numeric_limits<double>::infinity()) const;
  // Whether some point within r of (x, y) in XY (distance < r) lies strictly above z.
  bool any_above(double x, double y, double r, double z) const;

  // Every point within r of (x, y) in XY (distance <= r), by index in the cloud.
  void within(double x, double y, double r, std::vector<int>& out) const;

  // The pyramid, for searches of their own (the tool drop's): level l's blocks are 2^l cells wide;
  // the highest z in a block (-infinity when empty), and the squared distance from (x, y) to it.
  int levels() const { return static_cast<int>(levels_.size()); }
  int level_nx(int l) const { return level_nx_[static_cast<std::size_t>(l)]; }
  int level_ny(int l) const { return level_ny_[static_cast<std::size_t>(l)]; }
  double block_top(int l, int i, int j) const { return level_max(l, i, j); }
  double block_distance2(int l, int i, int j, double x, double y) const;
  // The level whose blocks are about r wide, and its blocks overlapping the square of half-side r.
  int start_level(double r) const;
  bool block_range(int l, double x, double y, double r, int& i0, int& i1, int& j0, int& j1) const;

 private:
  std::size_t cell_id(int i, int j) const { return static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i); }
  // The pyramid: level l's cell (i, j) covers level 0's cells [i 2^l, (i + 1) 2^l) x [j 2^l, (j + 1) 2^l).
  double level_max(int l, int i, int j) const { return levels_[static_cast<std::size_t>(l)][static_cast<std::size_t>(j) * static_cast<std::size_t>(level_nx_[static_cast<std::size_t>(l)]) + static_cast<std::size_t>(i)]; }
  double block_far_distance2(int l, int i, int j, double x, double y) const;
  void max_in_block(int l, int i, int j, double x, double y, double r2, double& best) const;
  bool above_in_block(int l, int i, int j, double x, double y, double r2, double z) const;

  double cell_ = 1, x0_ = 0, y0_ = 0;
  int nx_ = 0, ny_ = 0;
  std::vector<BinnedPoint> points_;    // sorted by cell
  std::vector<std::size_t> start_;     // cell c's points are [start_[c], start_[c + 1])
  std::vector<std::vector<double>> levels_;  // level 0: each cell's max z (-inf when empty)
  std::vector<int> level_nx_, level_ny_;
};

}  // namespace drom::geometry
