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
  // The POD of the instants' snapshots: a_l = U_l, b_l = sigma_l V_l, bound = sum of dropped sigma.
  const Pod pod = truncated_pod(history, tolerance, PodNorm::Max);
  space_ = pod.modes;
  time_ = Eigen::MatrixXd::Zero(times_.size(), pod.rank());
  time_.bottomRows(times.size()) = pod.right * pod.singular_values.head(pod.rank()).asDiagonal();
  bound_ = pod.max_bound;
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

void SpaceTimeField::time_factors(double t, Eigen::Ref<Eigen::VectorXd> out) const {
  if (times_.size() == 0) {
    out.setZero();
  } else if (times_.size() == 1) {
    out = time_.row(0).transpose();
  } else {
    const auto [i, w] = locate_time(times_, t);
    out = ((1 - w) * time_.row(i) + w * time_.row(i + 1)).transpose();
  }
}

}  // namespace drom::reduce
