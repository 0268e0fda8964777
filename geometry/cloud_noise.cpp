#include "geometry/cloud_noise.hpp"

#include "geometry/cloud_kdtree.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

namespace drom::geometry {

double scan_noise(std::span<const Eigen::Vector3d> points, int samples) {
  if (points.size() < 25) return 0;
  return scan_noise(points, CloudKdTree(points), samples);
}

double scan_noise(std::span<const Eigen::Vector3d> points, const CloudKdTree& tree, int samples) {
  constexpr int k = 24;
  if (points.size() < static_cast<std::size_t>(k) + 1) return 0;
  std::mt19937 rng(2045);
  std::uniform_int_distribution<std::size_t> pick(0, points.size() - 1);
  const std::size_t m = std::min<std::size_t>(points.size(), static_cast<std::size_t>(samples));
  std::vector<double> sigma;
  std::vector<int> near;
  std::vector<double> d2;
  Eigen::MatrixXd a(k, 6);
  Eigen::VectorXd w(k);
  for (std::size_t s = 0; s < m; ++s) {
    const std::size_t i = m == points.size() ? s : pick(rng);
    tree.nearest(points[i], k, near, d2);
    Eigen::Vector3d mean = Eigen::Vector3d::Zero();
    for (const int j : near) mean += points[static_cast<std::size_t>(j)];
    mean /= k;
    Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
    for (const int j : near) cov += (points[static_cast<std::size_t>(j)] - mean) * (points[static_cast<std::size_t>(j)] - mean).transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
    const Eigen::Vector3d n = eig.eigenvectors().col(0), u = eig.eigenvectors().col(2), v = eig.eigenvectors().col(1);
    for (int r = 0; r < k; ++r) {
      const Eigen::Vector3d d = points[static_cast<std::size_t>(near[static_cast<std::size_t>(r)])] - mean;
      const double x = d.dot(u), y = d.dot(v);
      a.row(r) << 1, x, y, x * x, x * y, y * y;
      w(r) = d.dot(n);
    }
    const Eigen::VectorXd c = a.colPivHouseholderQr().solve(w);
    const double residual = (a * c - w).squaredNorm();
    sigma.push_back(std::sqrt(residual / (k - 6)));
  }
  std::nth_element(sigma.begin(), sigma.begin() + static_cast<std::ptrdiff_t>(sigma.size() / 2), sigma.end());
  return sigma[sigma.size() / 2];
}

}  // namespace drom::geometry
