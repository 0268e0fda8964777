#pragma once
// A mean and covariance (divided by n) kept up to date as points join and leave a set: Welford's
// updates, which give the seed's incremental formulas (Herraz eqs. 3.5-3.6, Annex D) without their
// raw second moments' cancellation.
#include <Eigen/Core>

namespace drom::paths {

template <int D>
class RunningCovariance {
 public:
  using Vector = Eigen::Matrix<double, D, 1>;
  using Matrix = Eigen::Matrix<double, D, D>;

  void add(const Vector& x) {
    ++n_;
    const Vector delta = x - mean_;
    mean_ += delta / static_cast<double>(n_);
    scatter_ += delta * (x - mean_).transpose();
  }
  // `x` must be a point of the set.
  void remove(const Vector& x) {
    if (n_ <= 1) {
      *this = RunningCovariance();
      return;
    }
    const Vector mean_before = (static_cast<double>(n_) * mean_ - x) / static_cast<double>(n_ - 1);
    scatter_ -= (x - mean_before) * (x - mean_).transpose();
    mean_ = mean_before;
    --n_;
  }

  int count() const { return n_; }
  const Vector& mean() const { return mean_; }
  Matrix covariance() const { return n_ > 0 ? Matrix(scatter_ / static_cast<double>(n_)) : Matrix(Matrix::Zero()); }

 private:
  int n_ = 0;
  Vector mean_ = Vector::Zero();
  Matrix scatter_ = Matrix::Zero();
};

}  // namespace drom::paths
