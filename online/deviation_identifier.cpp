#include "online/deviation_identifier.hpp"

#include <Eigen/QR>

#include <cmath>
#include <stdexcept>

namespace drom::online {

DeviationIdentifier::DeviationIdentifier(reduce::DeviationGrid grid, Eigen::MatrixXd basis, double nominal_z)
    : grid_(grid), basis_(std::move(basis)), nominal_z_(nominal_z) {
  if (basis_.rows() != grid_.size()) throw std::invalid_argument("deviation basis: one row per grid point expected");
  normal_ = Eigen::MatrixXd::Zero(basis_.cols(), basis_.cols());
  rhs_ = Eigen::VectorXd::Zero(basis_.cols());
}

Eigen::RowVectorXd DeviationIdentifier::row(double x, double y) const {
  Eigen::RowVectorXd g = Eigen::RowVectorXd::Zero(basis_.cols());
  for (const auto& [i, w] : grid_.weights(x, y)) g += w * basis_.row(i);
  return g;
}

DeviationReport DeviationIdentifier::add_points(std::span<const MeasuredPoint> points) {
  DeviationReport report;
  for (const auto& p : points) {
    if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) {
      ++report.invalid;
      continue;
    }
    if (!grid_.contains(p.x, p.y)) {
      ++report.outside;
      continue;
    }
    const Eigen::RowVectorXd g = row(p.x, p.y);
    const double d = p.z - nominal_z_;
    normal_.noalias() += g.transpose() * g;
    rhs_.noalias() += g.transpose() * d;
    sum_squares_ += d * d;
    ++report.used;
  }
  points_ += report.used;
  return report;
}

Eigen::VectorXd DeviationIdentifier::coefficients() const {
  if (points_ == 0) return Eigen::VectorXd::Zero(basis_.cols());
  Eigen::CompleteOrthogonalDecomposition<Eigen::MatrixXd> cod(normal_);
  cod.setThreshold(1e-12);
  return cod.solve(rhs_);
}

double DeviationIdentifier::deviation(double x, double y, const Eigen::VectorXd& c) const { return row(x, y).dot(c); }
double DeviationIdentifier::deviation(double x, double y) const { return deviation(x, y, coefficients()); }

double DeviationIdentifier::residual_rms() const {
  if (points_ == 0) return 0;
  const Eigen::VectorXd c = coefficients();
  // sum (d - g c)^2 = sum d^2 - 2 c^T rhs + c^T H c
  return std::sqrt(std::max(0.0, (sum_squares_ - 2 * c.dot(rhs_) + c.dot(normal_ * c)) / static_cast<double>(points_)));
}

}  // namespace drom::online
