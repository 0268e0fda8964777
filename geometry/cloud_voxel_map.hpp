#pragma once
// The voxel map of a cloud (Makki 2009 §2.2.2, after Osty et al. 1999): space cut into cubes of one
// edge; a voxel is full when it holds points, and carries their barycentre and the normal of their
// least-squares plane (unoriented; none under 3 points, and the seed asks 20 for a stable plane).
// Sparse (OpenVDB trees, kept out of this header): a scanned part's voxels, not its bounding box's.
// Z-level roughing tests the tool against the barycentres (paths/copy/cloud_roughing.hpp).
#include <Eigen/Core>

#include <memory>
#include <span>
#include <vector>

namespace drom::geometry {

struct CloudVoxel {
  Eigen::Vector3i coord = Eigen::Vector3i::Zero();  // index: the voxel spans [coord, coord + 1) x edge
  int count = 0;
  Eigen::Vector3d barycentre = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal = Eigen::Vector3d::Zero();  // least-squares plane's (unit), zero under 3 points
  double planarity = 0;  // smallest over middle eigenvalue of the points' covariance (0: a perfect plane)
};

class CloudVoxelMap {
 public:
  // Throws std::invalid_argument on a non-positive edge.
  CloudVoxelMap(std::span<const Eigen::Vector3d> points, double edge);
  ~CloudVoxelMap();
  CloudVoxelMap(CloudVoxelMap&&) noexcept;
  CloudVoxelMap& operator=(CloudVoxelMap&&) noexcept;

  double edge() const { return edge_; }
  std::size_t full_voxels() const;
  bool full(const Eigen::Vector3d& p) const;
  int count(const Eigen::Vector3d& p) const;
  // Every full voxel, in index order (z fastest).
  std::vector<CloudVoxel> voxels() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  double edge_ = 1;
};

}  // namespace drom::geometry
