#pragma once
// How long the machine takes over a finishing pass, a link between passes, and a move between
// zones. This is the one place path planning asks; until machine/'s feed and cycle-time predictor
// is merged it answers with the seed's jerk-limited closed forms (Herraz §1.6.2), completed with
// the case the seed leaves out (acceleration limit reached, feed not).
#include <Eigen/Core>

#include <vector>

namespace drom::paths {

// Limits along the path (the seed's single set for all axes), mm and s.
struct Kinematics {
  double feed = 5000.0 / 60;  // V, mm/s (the seed's 5 m/min)
  double acceleration = 6000;  // A, mm/s^2
  double jerk = 40000;         // J, mm/s^3
};

// A straight move of `length` from rest to rest under a symmetric 7-phase jerk-limited profile:
// t = L/V + V/A + A/J where V and A are reached (seed eq. 1.13), L/V + 2 sqrt(V/J) where only V is
// (eq. 1.14), 4 (L / 2J)^(1/3) where neither is (eq. 1.15, with 2l = L), and 2 (v/A + A/J) with
// v^2 + v A^2/J - A L = 0 where A is reached but V is not.
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
