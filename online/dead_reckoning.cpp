#include "online/dead_reckoning.hpp"

#include "reduce/space_time_field.hpp"

#include <algorithm>
#include <stdexcept>
#include <string>

namespace drom::online {

DeadReckoning::DeadReckoning(Eigen::MatrixXd path, std::vector<int> sync, std::shared_ptr<const machine::ProgramClock> motion)
    : path_(std::move(path)), sync_(std::move(sync)), motion_(std::move(motion)) {
  if (path_.cols() != 4 || path_.rows() < 2) throw std::invalid_argument("dead reckoning: the path needs at least two waypoints (x, y, z, program time)");
  for (Eigen::Index i = 1; i < path_.rows(); ++i)
    if (!(path_(i, 3) >= path_(i - 1, 3))) throw std::invalid_argument("dead reckoning: program times must not decrease (waypoint " + std::to_string(i) + ")");
  if (!std::is_sorted(sync_.begin(), sync_.end())) throw std::invalid_argument("dead reckoning: synchronized waypoints must be sorted");
  for (int w : sync_)
    if (w < 0 || w >= path_.rows()) throw std::invalid_argument("dead reckoning: synchronized waypoint " + std::to_string(w) + " is not on the path");
}

void DeadReckoning::edge(int waypoint, double clock) {
  const auto it = std::lower_bound(sync_.begin(), sync_.end(), waypoint);
  if (it == sync_.end() || *it != waypoint) throw std::invalid_argument("dead reckoning: waypoint " + std::to_string(waypoint) + " raises no edge");
  last_ = static_cast<int>(it - sync_.begin());
  last_clock_ = clock;
}

double DeadReckoning::program_time(double clock) const {
  const double first = path_(sync_.empty() ? path_.rows() - 1 : sync_.front(), 3);
  if (last_ < 0) return std::min(motion_ ? motion_->program_time(clock) : clock, first);
  const double t0 = path_(sync_[static_cast<std::size_t>(last_)], 3);
  const double cap = static_cast<std::size_t>(last_ + 1) < sync_.size() ? path_(sync_[static_cast<std::size_t>(last_ + 1)], 3) : path_(path_.rows() - 1, 3);
  const double since = std::max(0.0, clock - last_clock_);
  // With a motion model: where the machine, having passed the edge's waypoint, gets in that time.
  const double believed = motion_ ? motion_->program_time(motion_->real_time(t0) + since) : t0 + since;
  return std::min(cap, believed);
}

Eigen::Vector3d path_position(const Eigen::MatrixXd& path, double t) {
  const Eigen::VectorXd times = path.col(3);
  const auto [i, w] = reduce::locate_time(times, t);
  return ((1 - w) * path.row(i).head<3>() + w * path.row(i + 1).head<3>()).transpose();
}

}  // namespace drom::online
