#pragma once
// The area of a drop frame's XY that a path covers: cells of an occupancy grid marked where the
// points to machine (a packet's) fall, grown by a margin so that the tool reaches the area's edge.
// The nodes of a path lie inside; the tool is still dropped on the whole cloud (Makki §2.3.7), so it
// never gouges what lies outside.
#include <Eigen/Core>

#include <span>
#include <vector>

namespace drom::paths {

class CloudArea {
 public:
  CloudArea() = default;
  // The cells (of `cell` mm) holding a point, grown by `margin` mm (a disk, measured between cell centres).
  CloudArea(std::span<const Eigen::Vector3d> drop_frame_points, double cell, double margin);
  // A rectangle.
  static CloudArea rectangle(double x0, double x1, double y0, double y1);

  bool empty() const { return count_ == 0; }
  bool contains(double x, double y) const;
  double x_min() const { return x_min_; }
  double x_max() const { return x_max_; }
  double y_min() const { return y_min_; }
  double y_max() const { return y_max_; }
  double area() const;  // mm^2

 private:
  double cell_ = 1, x0_ = 0, y0_ = 0;
  int nx_ = 0, ny_ = 0;
  std::vector<char> inside_;  // empty: the whole bounding rectangle
  std::size_t count_ = 0;
  double x_min_ = 0, x_max_ = 0, y_min_ = 0, y_max_ = 0;
};

}  // namespace drom::paths
