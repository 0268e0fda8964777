#pragma once
// A history over a surface, f(node, t), kept as sum_l a_l(node) b_l(t) (docs/design.md §5): the SVD of the
// nodes x times array truncated at the fewest terms whose measured max error at the stored instants
// is within `tolerance` (the history's unit). Between stored instants it is linear in time,
// as the full history would be; before the first instant it goes linearly to `start_value` at
// time `start` (0 displacement when the machining starts), and after the last it stays there.
#include "reduce/pod.hpp"

#include <Eigen/Core>

#include <vector>

namespace drom::reduce {

class SpaceTimeField {
 public:
  SpaceTimeField() = default;
  // history: nodes x times; times increasing. A start time before times[0] adds a zero instant there.
  SpaceTimeField(const Eigen::MatrixXd& history, const Eigen::VectorXd& times, double tolerance, double start = -1);
  // From stored factors (a model file).
  SpaceTimeField(Eigen::MatrixXd space, Eigen::MatrixXd time, Eigen::VectorXd times, double bound);

  int terms() const { return static_cast<int>(space_.cols()); }
  double bound() const { return bound_; }  // the truncation's max error at the stored instants (measured)
  const Eigen::MatrixXd& space() const { return space_; }  // nodes x terms: a_l
  const Eigen::MatrixXd& time() const { return time_; }    // instants x terms: b_l (singular values folded in)
  const Eigen::VectorXd& times() const { return times_; }

  // b(t): the time factors at t (terms); the second form writes into `out` (sized terms()), for
  // callers that must not allocate.
  Eigen::VectorXd time_factors(double t) const;
  void time_factors(double t, Eigen::Ref<Eigen::VectorXd> out) const;
  // f at every node at time t (nodes).
  Eigen::VectorXd at(double t) const { return space_ * time_factors(t); }
  double at(Eigen::Index node, double t) const;  // one node: no temporary (the sensor's brute-force readings call it per point)

 private:
  // The stored instants t is read between and the later one's weight (one instant: itself alone).
  struct TimeBlend {
    Eigen::Index lo, hi;
    double w;
  };
  TimeBlend blend(double t) const;  // needs an instant

  Eigen::MatrixXd space_, time_;
  Eigen::VectorXd times_;
  double bound_ = 0;
};

// Where t falls among increasing instants: the interval i (times[i] <= t <= times[i+1]) and the weight
// of times[i+1], clamped to the ends.
struct TimeInterval {
  Eigen::Index i = 0;
  double weight = 0;
};
TimeInterval locate_time(const Eigen::VectorXd& times, double t);

}  // namespace drom::reduce
