#pragma once
// Online identification of the blank's geometric deviation (docs/design.md §8, seed §2.2.4, eqs.
// 2.15-2.18): laser points are fitted, in least squares, in a basis of deviation surfaces on a grid
// (the POD modes of a deviation family, or the family itself); the fit extrapolates the deviation
// over the whole area, where the tool has not been yet. Normal equations are accumulated profile by
// profile; the solution is the minimum-norm least-squares one, so a redundant basis (a raw family)
// works too.
#include "online/predictor.hpp"
#include "reduce/deviation_family.hpp"

#include <Eigen/Core>

#include <span>

namespace drom::online {

struct DeviationReport {
  int used = 0, outside = 0, invalid = 0;
};

class DeviationIdentifier {
 public:
  // basis: grid points x r; the nominal surface is z = nominal_z (the deviation is z - nominal_z).
  DeviationIdentifier(reduce::DeviationGrid grid, Eigen::MatrixXd basis, double nominal_z = 0);

  DeviationReport add_points(std::span<const MeasuredPoint> points);
  // Least-squares coefficients (minimum norm where the points do not determine them).
  Eigen::VectorXd coefficients() const;
  double deviation(double x, double y) const;  // with the current coefficients
  double deviation(double x, double y, const Eigen::VectorXd& coefficients) const;
  double altitude(double x, double y, const Eigen::VectorXd& coefficients) const { return nominal_z_ + deviation(x, y, coefficients); }
  // RMS of the used points against the current fit.
  double residual_rms() const;
  long long points() const { return points_; }
  int rank() const { return static_cast<int>(basis_.cols()); }

 private:
  Eigen::RowVectorXd row(double x, double y) const;
  reduce::DeviationGrid grid_;
  Eigen::MatrixXd basis_;
  double nominal_z_;
  Eigen::MatrixXd normal_;
  Eigen::VectorXd rhs_;
  double sum_squares_ = 0;
  long long points_ = 0;
};

}  // namespace drom::online
