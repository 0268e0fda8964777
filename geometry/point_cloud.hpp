#pragma once
// A point cloud as a scanner delivers it (Makki 2009, seed 001): points in the part frame, in mm,
// already registered, with a unit normal per point when one is known. Clouds are machined as they are,
// with no surface rebuilt: the tool is dropped on the points along its axis, in a frame whose Z is
// that axis (frame_along), so every path computation sees "the tool axis is +Z".
#include <Eigen/Core>

#include <span>
#include <string>
#include <vector>

namespace drom::geometry {

// Points a reader or a cleaning step left out, counted for the run's report.
struct DroppedPoints {
  std::size_t not_finite = 0;     // a NaN or infinite coordinate or normal component
  std::string first_not_finite;   // where the first one was: "file: line N: ..." or "file: byte N: ..."
  std::size_t far_outliers = 0;   // geometry/cloud_outliers.hpp
};

struct PointCloud {
  std::string origin;                    // the file it came from, or what made it (for messages)
  DroppedPoints dropped;
  std::vector<Eigen::Vector3d> points;   // mm
  std::vector<Eigen::Vector3d> normals;  // empty, or one unit normal per point (outward: out of the material)
  std::size_t size() const { return points.size(); }
  bool has_normals() const { return !normals.empty(); }
};

struct Box3 {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = Eigen::Vector3d::Constant(-1e300);
  bool empty() const { return (lo.array() > hi.array()).any(); }
  void add(const Eigen::Vector3d& p) { lo = lo.cwiseMin(p), hi = hi.cwiseMax(p); }
  Eigen::Vector3d centre() const { return 0.5 * (lo + hi); }
  Eigen::Vector3d size() const { return hi - lo; }
};
Box3 bounding_box(std::span<const Eigen::Vector3d> points);

// A rotation Q taking `axis` (unit) onto +Z: Q * axis = e_z. Its rows are the frame's X, Y and Z in the
// part frame; X is the part's X made orthogonal to the axis (the part's Y when the axis lies along X),
// so a drop frame keeps the part's X as its feed direction where it can.
Eigen::Matrix3d frame_along(const Eigen::Vector3d& axis);

// Q * p for every point (into a drop frame), and Q^T back.
std::vector<Eigen::Vector3d> rotated(std::span<const Eigen::Vector3d> points, const Eigen::Matrix3d& q);

}  // namespace drom::geometry
