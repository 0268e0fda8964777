#pragma once
// k-d trees over a cloud (nanoflann, Debian's libnanoflann-dev; kept out of this header): in 3D for
// nearest neighbours (PCA normals, the nearest packet of a leftover point), and over XY in a drop
// frame, the alternative to CloudBins for the tool drop (bench/clouds_bench.cpp measures both).
#include <Eigen/Core>

#include <memory>
#include <span>
#include <vector>

namespace drom::geometry {

class CloudKdTree {
 public:
  // `dimensions`: 3 (x, y, z) or 2 (x, y only: distances in a drop frame's XY). The points are
  // copied.
  CloudKdTree(std::span<const Eigen::Vector3d> points, int dimensions = 3);
  ~CloudKdTree();
  CloudKdTree(CloudKdTree&&) noexcept;
  CloudKdTree& operator=(CloudKdTree&&) noexcept;

  std::size_t size() const;
  // The k nearest points (fewer when the cloud is smaller), nearest first: indices and squared distances.
  void nearest(const Eigen::Vector3d& p, int k, std::vector<int>& indices, std::vector<double>& squared_distances) const;
  // The nearest point's index (-1 for an empty tree).
  int nearest(const Eigen::Vector3d& p) const;
  // Every point within distance r (<= r), in no particular order.
  void within(const Eigen::Vector3d& p, double r, std::vector<int>& out) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace drom::geometry
