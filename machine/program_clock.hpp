#pragma once
// Program time against real time, for a path timed at its programmed feed (waypoints x, y, z and the
// program time at which the program reaches each, as the offline model stores it): the machine's
// predicted motion along the same waypoints (feed_prediction.hpp) maps the real time since the start
// to the program time of the point the tool has reached, and back. Both maps increase.
// Each segment between waypoints is a block programmed to last its program-time span (a segment of
// zero length that lasts is a dwell); the machine joins them as it joins any blocks.
#include "machine/feed_prediction.hpp"

#include <Eigen/Core>

namespace drom::machine {

class ProgramClock {
 public:
  // `path`: rows x, y, z (the tool tip, part frame = program frame of a 3-axis machine), program time
  // (non-decreasing). `feed_override` scales the programmed feed (the machine runs at override x it).
  ProgramClock(const Eigen::MatrixXd& path, const Machine& machine, double feed_override = 1);

  double program_time(double real_time) const;
  double real_time(double program_time) const;
  double real_duration() const { return prediction_.cycle_time; }
  double program_duration() const { return program_times_[program_times_.size() - 1]; }
  const FeedPrediction& prediction() const { return prediction_; }

 private:
  Eigen::VectorXd program_times_;  // per waypoint
  FeedPrediction prediction_;      // one block per segment
};

}  // namespace drom::machine
