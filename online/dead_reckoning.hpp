#pragma once
// Position synchronization (docs/design.md §7; seed §2.2.5.2, fig. 2.26): the controller raises an edge
// when the tool passes chosen waypoints; between edges the tool's progress is estimated from the last
// edge, along the programmed path, and never past the next synchronized waypoint: at the programmed
// feed, or with a model of the machine's real motion (machine/program_clock.hpp: the feed it really
// reaches, slower into corners and at the ends of passes). Everything downstream (the predictor, the
// sensor's believed positions) works in program time: the time at which the program, run at its
// programmed feed, reaches a point.
#include "machine/program_clock.hpp"

#include <Eigen/Core>

#include <memory>

#include <vector>

namespace drom::online {

// The tool tip on a path (waypoints x, y, z, program time) at program time t, linear between
// waypoints and held at the ends.
Eigen::Vector3d path_position(const Eigen::MatrixXd& path, double t);

class DeadReckoning {
 public:
  // path: waypoints x, y, z, program time (increasing); sync: indices of the waypoints that raise an
  // edge (sorted).
  // `motion`: the machine's predicted real motion along `path`; null: the programmed feed.
  DeadReckoning(Eigen::MatrixXd path, std::vector<int> sync, std::shared_ptr<const machine::ProgramClock> motion = nullptr);

  // The controller's edge for synchronized waypoint `waypoint`, received at clock time `clock`.
  void edge(int waypoint, double clock);
  // Estimated program time at clock time `clock` (before any edge: the clock itself).
  double program_time(double clock) const;
  Eigen::Vector3d position(double clock) const { return position_at_program_time(program_time(clock)); }
  Eigen::Vector3d position_at_program_time(double t) const { return path_position(path_, t); }

  const Eigen::MatrixXd& path() const { return path_; }
  const std::vector<int>& sync() const { return sync_; }

 private:
  Eigen::MatrixXd path_;
  std::vector<int> sync_;
  std::shared_ptr<const machine::ProgramClock> motion_;
  int last_ = -1;             // index into sync_ of the last edge
  double last_clock_ = 0;
};

}  // namespace drom::online
