#include "geometry/part_shape.hpp"

#include <algorithm>

#include <cmath>

namespace drom::geometry {

PartShape PartShape::plate(double lx, double ly, double thickness) {
  PartShape s;
  s.kind_ = Kind::Plate;
  s.lu_ = lx;
  s.lv_ = ly;
  s.thickness_ = thickness;
  return s;
}

PartShape PartShape::panel(double lx, double ly, double thickness, double outer_radius) {
  PartShape s = plate(lx, ly, thickness);
  s.kind_ = Kind::Panel;
  s.outer_radius_ = outer_radius;
  return s;
}

PartShape PartShape::block(const Eigen::Vector3d& min_corner, const Eigen::Vector3d& max_corner) {
  const Eigen::Vector3d d = max_corner - min_corner;
  PartShape s = plate(d.x(), d.y(), d.z());
  s.kind_ = Kind::Block;
  s.origin_ = min_corner;
  return s;
}

Eigen::Vector3d PartShape::from_parametric(const Eigen::Vector3d& p) const {
  if (kind_ != Kind::Panel) return origin_ + p;
  const double r = outer_radius_ - thickness_ + p.z();
  const double phi = (p.x() - 0.5 * lu_) / outer_radius_;
  return {0.5 * lu_ + r * std::sin(phi), p.y(), r * std::cos(phi) - (outer_radius_ - thickness_)};
}

Eigen::Vector3d PartShape::to_parametric(const Eigen::Vector3d& x) const {
  if (kind_ != Kind::Panel) return x - origin_;
  const double dx = x.x() - 0.5 * lu_;
  const double dz = x.z() + (outer_radius_ - thickness_);
  const double r = std::hypot(dx, dz);
  const double phi = std::atan2(dx, dz);
  return {0.5 * lu_ + phi * outer_radius_, x.y(), r - (outer_radius_ - thickness_)};
}

double PartShape::reduced_thickness(const Eigen::Vector3d& x) const {
  return 2.0 * to_parametric(x).z() / thickness_ - 1.0;
}

Eigen::Matrix3d PartShape::local_frame(const Eigen::Vector3d& x) const {
  if (kind_ != Kind::Panel) return Eigen::Matrix3d::Identity();
  const double phi = (to_parametric(x).x() - 0.5 * lu_) / outer_radius_;
  Eigen::Matrix3d frame;
  frame.col(0) = Eigen::Vector3d(std::cos(phi), 0, -std::sin(phi));
  frame.col(1) = Eigen::Vector3d(0, 1, 0);
  frame.col(2) = Eigen::Vector3d(std::sin(phi), 0, std::cos(phi));
  return frame;
}

double PartShape::signed_distance(const Eigen::Vector3d& x) const {
  // Box in parametric coordinates; for a panel u is an arc length at the outer radius, converted to
  // a length at the point's own radius so the distance to the end faces stays metric.
  const Eigen::Vector3d p = to_parametric(x);
  double du_scale = 1.0;
  if (kind_ == Kind::Panel) du_scale = (outer_radius_ - thickness_ + p.z()) / outer_radius_;
  const Eigen::Vector3d half(0.5 * lu_, 0.5 * lv_, 0.5 * thickness_);
  Eigen::Vector3d q = (p - half).cwiseAbs() - half;
  q.x() *= du_scale;
  const Eigen::Vector3d outside = q.cwiseMax(0.0);
  return outside.norm() + std::min(q.maxCoeff(), 0.0);
}

}  // namespace drom::geometry
