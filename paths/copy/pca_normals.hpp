#pragma once
// Normals by principal component analysis, the estimate sphere launching is compared with (Makki 2009
// §3-2.4 compares with a least-squares plane per voxel; Hoppe et al. 1992 per point): the direction of
// least spread of each point's k nearest neighbours. Its sign is arbitrary, so it is oriented outward
// either like the nearest sphere-launched normal, or, with nothing to copy, by Hoppe's propagation:
// along the minimum spanning tree of the k-nearest-neighbour graph (weight 1 - |n_i . n_j|) from the
// highest point, oriented +Z (out of a part scanned from above).
#include "paths/copy/sphere_normals.hpp"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace drom::paths {

// Unoriented unit normals at the points `at` of the cloud (k >= 3 neighbours, the point included).
std::vector<Eigen::Vector3d> pca_normals(std::span<const Eigen::Vector3d> cloud, std::span<const int> at, int neighbours = 16);

// Flips each normal (at cloud point at[i]) to agree with the reference normal of the nearest point
// that has one.
void orient_like(std::span<const Eigen::Vector3d> cloud, std::span<const int> at, std::vector<Eigen::Vector3d>& normals, const PointNormals& reference);

// Hoppe's propagation over the points at[i] (consistent signs, the highest point's normal up).
void orient_by_propagation(std::span<const Eigen::Vector3d> cloud, std::span<const int> at, std::vector<Eigen::Vector3d>& normals, int neighbours = 16);

}  // namespace drom::paths
