#include "paths/finish/pca.hpp"

#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <cmath>
#include <numbers>
#include <stdexcept>

namespace drom::paths {

double reduce_azimuth(double angle) {
  constexpr double pi = std::numbers::pi;
  angle = std::fmod(angle, pi);
  if (angle >= pi / 2) angle -= pi;
  if (angle < -pi / 2) angle += pi;
  return angle;
}

PcaPlane pca_plane(const Eigen::Matrix3d& covariance, const Eigen::Vector3d& mean, int count) {
  PcaPlane p;
  p.count = count;
  p.mean = mean;
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eigen(covariance);
  // Eigen sorts ascending.
  p.lambda = Eigen::Vector3d(eigen.eigenvalues()(2), eigen.eigenvalues()(1), std::max(0.0, eigen.eigenvalues()(0)));
  Eigen::Vector3d x1 = eigen.eigenvectors().col(2), x2 = eigen.eigenvectors().col(1);
  Eigen::Vector3d x3 = x1.cross(x2);
  if (x3.z() < 0) {
    x2 = -x2;
    x3 = -x3;
  }
  p.axes.col(0) = x1;
  p.axes.col(1) = x2;
  p.axes.col(2) = x3;
  const double l1 = std::max(p.lambda(0), 0.0), l2 = std::max(p.lambda(1), 0.0);
  p.shape_factor = l2 > 0 ? std::sqrt(l1 / l2) : std::numeric_limits<double>::infinity();
  p.size = 12 * std::sqrt(l1 * l2);
  p.width = std::sqrt(12 * l1);
  p.height = std::sqrt(12 * l2);
  p.slope = std::acos(std::min(1.0, std::abs(x3.z())));
  p.principal_azimuth = reduce_azimuth(std::atan2(x1.y(), x1.x()));
  p.steepest_azimuth = x3.head<2>().norm() > 0 ? reduce_azimuth(std::atan2(x3.y(), x3.x())) : 0.0;
  const Eigen::Vector3d up = Eigen::Vector3d::UnitZ() - x3.z() * x3;
  if (up.norm() > 1e-12) p.steepest_direction = up.normalized();
  return p;
}

PcaPlane pca_plane(const std::vector<Eigen::Vector3d>& points) {
  if (points.size() < 3) throw std::invalid_argument("a PCA plane needs at least 3 points");
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  for (const auto& q : points) mean += q;
  mean /= static_cast<double>(points.size());
  Eigen::Matrix3d c = Eigen::Matrix3d::Zero();
  for (const auto& q : points) c += (q - mean) * (q - mean).transpose();
  c /= static_cast<double>(points.size());
  return pca_plane(c, mean, static_cast<int>(points.size()));
}

double mean_slope(const std::vector<Eigen::Vector3d>& normals) {
  if (normals.empty()) return 0;
  double sum = 0;
  for (const auto& n : normals) sum += std::acos(std::min(1.0, std::abs(n.z())));
  return sum / static_cast<double>(normals.size());
}

double mean_steepest_azimuth(const std::vector<Eigen::Vector3d>& normals) {
  double c = 0, s = 0;
  for (const auto& n : normals) {
    const double h = n.head<2>().norm();
    if (h == 0) continue;
    const double a = std::atan2(n.y(), n.x());
    c += h * std::cos(2 * a);
    s += h * std::sin(2 * a);
  }
  if (c == 0 && s == 0) return 0;
  return reduce_azimuth(0.5 * std::atan2(s, c));
}

}  // namespace drom::paths
