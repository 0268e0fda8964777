#pragma once
// How long the machine takes over a finishing pass, a link between passes, and a move between
// zones, inside the search: each move rest to rest under machine/'s jerk-limited double S
// (machine/scurve.hpp) with the path's limits (the seed's model, Herraz §1.6.2, which machine/'s
// double S reproduces and completes). The program finally written is timed by machine/'s full
// feed predictor (junction speeds, per-axis limits) in finish_run.cpp; this cheaper model is what
// thousands of evaluations per K can afford (docs/finishing.md measures both).
#include <Eigen/Core>

#include <vector>

namespace drom::paths {

// Limits along the path (the seed's single set for all axes), mm and s.
struct Kinematics {
  double feed = 5000.0 / 60;  // V, mm/s (the seed's 5 m/min)
  double acceleration = 6000;  // A, mm/s^2
  double jerk = 40000;         // J, mm/s^3
};

// A straight move of `length` from rest to rest: machine/'s double S (the seed's eqs. 1.13-1.15 and
// the regime they leave out).
double rest_to_rest_time(double length, const Kinematics& limits);

class MoveTimer {
 public:
  MoveTimer(Kinematics cutting, Kinematics rapid) : cutting_(cutting), rapid_(rapid) {}

  // A finishing pass: one smooth run at the feed from rest to rest (the seed treats a pass as a
  // trajectory without sharp corners).
  double pass(const std::vector<Eigen::Vector3d>& points) const;
  // A zigzag link between the end of one pass and the start of the next, at the feed.
  double link(const Eigen::Vector3d& from, const Eigen::Vector3d& to) const;
  // A retract-traverse-plunge between two cutting points: up to `clear_z`, across and down at the
  // rapid limits, the last `approach` mm down at the cutting limits.
  double repositioning(const Eigen::Vector3d& from, const Eigen::Vector3d& to, double clear_z, double approach) const;

  const Kinematics& cutting() const { return cutting_; }
  const Kinematics& rapid() const { return rapid_; }

 private:
  Kinematics cutting_, rapid_;
};

double polyline_length(const std::vector<Eigen::Vector3d>& points);

}  // namespace drom::paths
