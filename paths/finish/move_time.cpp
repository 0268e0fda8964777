#include "paths/finish/move_time.hpp"

#include "machine/scurve.hpp"

#include <algorithm>
#include <cmath>

namespace drom::paths {

double rest_to_rest_time(double length, const Kinematics& k) {
  if (!(length > 0)) return 0;
  return machine::plan_double_s(0, 0, length, machine::MotionLimits{k.feed, k.acceleration, k.jerk}).duration();
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
