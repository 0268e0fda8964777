#include "paths/move_time.hpp"

#include <algorithm>
#include <cmath>

namespace drom::paths {

double rest_to_rest_time(double length, const Kinematics& k) {
  if (!(length > 0)) return 0;
  const double V = k.feed, A = k.acceleration, J = k.jerk;
  if (V * J >= A * A) {
    // A is reachable on the way to V.
    const double full = V * (V / A + A / J);  // distance of the acceleration and deceleration phases at V
    if (length >= full) return length / V + V / A + A / J;
    const double ramp = A * A / J;  // the speed gained while the jerk raises A from 0 and back
    const double v = 0.5 * (-ramp + std::sqrt(ramp * ramp + 4 * A * length));
    if (v >= ramp) return 2 * (v / A + A / J);
  } else if (length >= 2 * V * std::sqrt(V / J)) {
    return length / V + 2 * std::sqrt(V / J);
  }
  return 4 * std::cbrt(length / (2 * J));
}

double polyline_length(const std::vector<Eigen::Vector3d>& points) {
  double l = 0;
  for (std::size_t i = 1; i < points.size(); ++i) l += (points[i] - points[i - 1]).norm();
  return l;
}

double MoveTimer::pass(const std::vector<Eigen::Vector3d>& points) const { return rest_to_rest_time(polyline_length(points), cutting_); }

double MoveTimer::link(const Eigen::Vector3d& from, const Eigen::Vector3d& to) const { return rest_to_rest_time((to - from).norm(), cutting_); }

double MoveTimer::repositioning(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double clear_z, double approach) const {
  const double top = std::max({clear_z, from.z(), to.z()});
  const double down = top - to.z(), fast_down = std::max(0.0, down - approach);
  return rest_to_rest_time(top - from.z(), rapid_) + rest_to_rest_time((to - from).head<2>().norm(), rapid_) + rest_to_rest_time(fast_down, rapid_) +
         rest_to_rest_time(down - fast_down, cutting_);
}

}  // namespace drom::paths
