#include "geometry/point_cloud.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <stdexcept>

namespace drom::geometry {

Box3 bounding_box(std::span<const Eigen::Vector3d> points) {
  Box3 b;
  for (const auto& p : points) b.add(p);
  return b;
}

Eigen::Matrix3d frame_along(const Eigen::Vector3d& axis) {
  const double n = axis.norm();
  if (!(n > 0) || !std::isfinite(n)) throw std::invalid_argument("frame_along: the axis must be a finite non-zero vector");
  const Eigen::Vector3d z = axis / n;
  // Gram-Schmidt of the part's X against the axis; its Y when X is (nearly) the axis.
  Eigen::Vector3d x = Eigen::Vector3d::UnitX() - z.x() * z;
  if (x.norm() < 1e-6) x = Eigen::Vector3d::UnitY() - z.y() * z;
  x.normalize();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d q;
  q.row(0) = x.transpose();
  q.row(1) = y.transpose();
  q.row(2) = z.transpose();
  return q;
}

std::vector<Eigen::Vector3d> rotated(std::span<const Eigen::Vector3d> points, const Eigen::Matrix3d& q) {
  std::vector<Eigen::Vector3d> out(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) out[i] = q * points[i];
  return out;
}

}  // namespace drom::geometry
