#include "paths/copy/pca_normals.hpp"

#include "geometry/cloud_kdtree.hpp"

#include <Eigen/Eigenvalues>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <queue>
#include <stdexcept>

namespace drom::paths {

std::vector<Eigen::Vector3d> pca_normals(std::span<const Eigen::Vector3d> cloud, std::span<const int> at, int neighbours) {
  if (neighbours < 3) throw std::invalid_argument("PCA normals: at least 3 neighbours");
  const geometry::CloudKdTree tree(cloud, 3);
  std::vector<Eigen::Vector3d> normals(at.size(), Eigen::Vector3d::UnitZ());
  tbb::parallel_for(std::size_t(0), at.size(), [&](std::size_t i) {
    std::vector<int> near;
    std::vector<double> d2;
    tree.nearest(cloud[static_cast<std::size_t>(at[i])], neighbours, near, d2);
    if (near.size() < 3) return;
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const int k : near) mean += cloud[static_cast<std::size_t>(k)];
    mean /= static_cast<double>(near.size());
    Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
    for (const int k : near) {
      const Eigen::Vector3d v = cloud[static_cast<std::size_t>(k)] - mean;
      covariance += v * v.transpose();
    }
    normals[i] = Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d>(covariance).eigenvectors().col(0);
  });
  return normals;
}

void orient_like(std::span<const Eigen::Vector3d> cloud, std::span<const int> at, std::vector<Eigen::Vector3d>& normals, const PointNormals& reference) {
  if (reference.points.empty()) return;
  std::vector<Eigen::Vector3d> known;
  known.reserve(reference.points.size());
  for (const int k : reference.points) known.push_back(cloud[static_cast<std::size_t>(k)]);
  const geometry::CloudKdTree tree(known, 3);
  for (std::size_t i = 0; i < at.size(); ++i) {
    const int nearest = tree.nearest(cloud[static_cast<std::size_t>(at[i])]);
    if (normals[i].dot(reference.normals[static_cast<std::size_t>(nearest)]) < 0) normals[i] = -normals[i];
  }
}

void orient_by_propagation(std::span<const Eigen::Vector3d> cloud, std::span<const int> at, std::vector<Eigen::Vector3d>& normals, int neighbours) {
  const std::size_t n = at.size();
  if (n == 0) return;
  std::vector<Eigen::Vector3d> points(n);
  for (std::size_t i = 0; i < n; ++i) points[i] = cloud[static_cast<std::size_t>(at[i])];
  const geometry::CloudKdTree tree(points, 3);
  std::vector<std::vector<int>> graph(n);
  for (std::size_t i = 0; i < n; ++i) {
    std::vector<double> d2;
    tree.nearest(points[i], neighbours, graph[i], d2);
  }
  // The graph made symmetric, so every component is reached from any of its points.
  for (std::size_t i = 0; i < n; ++i)
    for (const int j : std::vector<int>(graph[i]))
      if (std::find(graph[static_cast<std::size_t>(j)].begin(), graph[static_cast<std::size_t>(j)].end(), static_cast<int>(i)) == graph[static_cast<std::size_t>(j)].end())
        graph[static_cast<std::size_t>(j)].push_back(static_cast<int>(i));
  std::vector<char> done(n, 0);
  // Prim's tree from each component's highest point; a point is oriented like its parent when it joins.
  std::vector<std::size_t> order(n);
  for (std::size_t i = 0; i < n; ++i) order[i] = i;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return points[a].z() > points[b].z(); });
  using Edge = std::pair<double, std::pair<int, int>>;  // weight, (parent, child)
  for (const std::size_t root : order) {
    if (done[root]) continue;
    if (normals[root].z() < 0) normals[root] = -normals[root];
    std::priority_queue<Edge, std::vector<Edge>, std::greater<Edge>> queue;
    const auto visit = [&](std::size_t i) {
      done[i] = 1;
      for (const int j : graph[i])
        if (!done[static_cast<std::size_t>(j)]) queue.push({1 - std::abs(normals[i].dot(normals[static_cast<std::size_t>(j)])), {static_cast<int>(i), j}});
    };
    visit(root);
    while (!queue.empty()) {
      const auto [weight, edge] = queue.top();
      queue.pop();
      const auto child = static_cast<std::size_t>(edge.second);
      if (done[child]) continue;
      if (normals[child].dot(normals[static_cast<std::size_t>(edge.first)]) < 0) normals[child] = -normals[child];
      visit(child);
    }
  }
}

}  // namespace drom::paths
