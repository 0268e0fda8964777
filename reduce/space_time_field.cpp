#include "reduce/space_time_field.hpp"

#include <algorithm>
#include <stdexcept>

namespace drom::reduce {

TimeInterval locate_time(const Eigen::VectorXd& times, double t) {
  const Eigen::Index n = times.size();
  if (n < 2 || t <= times[0]) return {0, 0.0};
  if (t >= times[n - 1]) return {n - 2, 1.0};
  const auto it = std::upper_bound(times.data(), times.data() + n, t);
  const Eigen::Index i = (it - times.data()) - 1;
  return {i, (t - times[i]) / (times[i + 1] - times[i])};
}

SpaceTimeField::SpaceTimeField(const Eigen::MatrixXd& history, const Eigen::VectorXd& times, double tolerance, double start) {
  if (history.cols() != times.size()) throw std::invalid_argument("space-time history: one column per instant expected");
  for (Eigen::Index k = 1; k < times.size(); ++k)
    if (!(times[k] > times[k - 1])) throw std::invalid_argument("space-time history: instants must increase");
  const bool add_start = times.size() > 0 && start >= 0 && start < times[0];
  const Eigen::Index offset = add_start ? 1 : 0;
  times_.resize(times.size() + offset);
  if (add_start) times_[0] = start;
  times_.tail(times.size()) = times;
  // The SVD of the instants' snapshots, a_l = U_l, b_l = sigma_l V_l, truncated at the fewest terms
  // whose *measured* max error at the stored instants meets the tolerance. The seed's bound (the sum
  // of the dropped singular values) is far too pessimistic here: the cut front travels with the tool,
  // so the singular values decay slowly while the error they leave is spread thin (measured on the
  // default plate: a bound-based truncation kept 670 of 813 terms per history for a 1e-6 mm actual
  // error). Between instants the form is linear in time, a convex combination: no larger error.
  const Pod full = truncated_pod(history, 0.0, PodNorm::Max);
  const Eigen::MatrixXd scaled_right = full.right * full.singular_values.head(full.rank()).asDiagonal();
  auto error_with = [&](int L) { return (history - full.modes.leftCols(L) * scaled_right.leftCols(L).transpose()).cwiseAbs().maxCoeff(); };
  int lo = 0, hi = full.rank();  // error_with(hi) is round-off
  if (error_with(0) <= tolerance) hi = 0;
  while (hi - lo > 1) {  // the max error is not monotone in L in general, but close: bisect, then check
    const int mid = (lo + hi) / 2;
    (error_with(mid) <= tolerance ? hi : lo) = mid;
  }
  space_ = full.modes.leftCols(hi);
  time_ = Eigen::MatrixXd::Zero(times_.size(), hi);
  // No term kept (a history within the tolerance everywhere): no block of an empty matrix, whose
  // null data Eigen would offset (UBSan; the database_fields fuzzer, finding 24).
  if (hi > 0) time_.bottomRows(times.size()) = scaled_right.leftCols(hi);
  bound_ = error_with(hi);
}

SpaceTimeField::SpaceTimeField(Eigen::MatrixXd space, Eigen::MatrixXd time, Eigen::VectorXd times, double bound)
    : space_(std::move(space)), time_(std::move(time)), times_(std::move(times)), bound_(bound) {
  if (space_.cols() != time_.cols() || time_.rows() != times_.size()) throw std::invalid_argument("space-time field: factor sizes disagree");
}

Eigen::VectorXd SpaceTimeField::time_factors(double t) const {
  Eigen::VectorXd b(terms());
  time_factors(t, b);
  return b;
}

SpaceTimeField::TimeBlend SpaceTimeField::blend(double t) const {
  if (times_.size() == 1) return {0, 0, 0.0};
  const auto [i, w] = locate_time(times_, t);
  return {i, i + 1, w};
}

double SpaceTimeField::at(Eigen::Index node, double t) const {
  if (terms() == 0 || times_.size() == 0) return 0.0;
  const auto [lo, hi, w] = blend(t);
  return space_.row(node).dot((1 - w) * time_.row(lo) + w * time_.row(hi));
}

void SpaceTimeField::time_factors(double t, Eigen::Ref<Eigen::VectorXd> out) const {
  if (terms() == 0) return;  // no row to take of an empty matrix (finding 24)
  if (times_.size() == 0) {
    out.setZero();
    return;
  }
  const auto [lo, hi, w] = blend(t);
  out = ((1 - w) * time_.row(lo) + w * time_.row(hi)).transpose();
}

}  // namespace drom::reduce
