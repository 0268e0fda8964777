#pragma once
// The feed a program really reaches on a machine, and its cycle time (Lavernhe et al. 2007 eq. 4,
// made complete; docs/machine.md states the model).
//
// 1. Per block, in the dimensionless space of the NC's joint interpolation (dq/ds per joint), the
//    path limits V_k/|dq_k/ds|, A_k/|dq_k/ds|, J_k/|dq_k/ds| per axis; their minima, and the axes that
//    set them, limit the path's speed, acceleration and jerk. The speed is further capped by the
//    programmed feed, by one block per interpolation cycle (ℓ / T_ipo), and on arcs by the axes'
//    centripetal acceleration and jerk (half of each is reserved for it).
// 2. At each junction the control rounds the corner in joint space within each axis's tolerance
//    (G642, G64 P): a blend of half-length δ = 6 ε / Δu_k (the jump of dq_k/ds) in which the axis
//    velocity changes with a triangular acceleration, the least jerk for the change. Blend mode
//    (corners on their own) bounds v by √(A_k δ / Δu_k) and ∛(J_k δ² / Δu_k); smooth mode (a
//    compressor joining consecutive corners) by the joint curvature κ = Δu_k / 2δ and its rate of
//    change: √(A_k / κ), ∛(J_k / κ'). A velocity jump the axis absorbs within one interpolation cycle
//    (A_k T_ipo) always passes. Exact stops, tool changes, dwells and rapid/feed changes stop the tool.
// 3. The path coordinate s (the tool tip's travel in the part frame, or the rotary travel in degrees
//    on a block that only turns) is planned with jerk-limited 7-phase S-curves between anchors where
//    the acceleration is zero: the start, the end, the junctions that limit the speed, and the blocks
//    whose cap the profile would exceed (which then run at their cap). Forward and backward sweeps
//    give the anchors' speeds; each stretch between two anchors is one double S, with the smallest
//    acceleration and jerk limits of its blocks.
#include "machine/kinematics.hpp"
#include "machine/machine_program.hpp"
#include "machine/scurve.hpp"

#include <array>
#include <string>
#include <vector>

namespace drom::machine {

enum class FeedLimit { ProgrammedFeed, AxisVelocity, InterpolationCycle, AxisAcceleration, AxisJerk, None };
const char* feed_limit_name(FeedLimit limit);
constexpr int kQuantities = 3;  // velocity, acceleration, jerk

struct BlockPrediction {
  double s_start = 0, length = 0;        // path coordinate: mm of tip travel (deg on a rotary-only block)
  bool rotary_only = false;
  double t_start = 0, duration = 0;      // s, predicted
  double programmed_duration = 0;        // s, at the programmed feed (0 for rapids)
  double cap = 0;                        // highest speed allowed on the block (units/s)
  FeedLimit cap_source = FeedLimit::None;
  int cap_axis = -1;                     // the joint setting the cap when an axis does
  std::array<double, kQuantities> path_limit{};  // the path's velocity, acceleration and jerk limits from the axes
  std::array<int, kQuantities> limiting_axis{-1, -1, -1};  // the joint that sets each of them
  double end_speed_limit = 0;            // the junction's limit at the block's end (units/s)
  // The block's length spent: at its cap, accelerating at the limit, in a jerk phase (speed changing
  // below the acceleration limit), or below the cap at constant speed.
  double length_at_cap = 0, length_accelerating = 0, length_in_jerk = 0;
  FeedLimit limit = FeedLimit::None;     // what holds the feed down over most of the block
  int limit_axis = -1;
  double min_speed = 0, max_speed = 0;   // units/s
};

struct PathState {
  double t = 0, s = 0, v = 0, a = 0, j = 0;
  std::size_t block = 0;
};

struct JointState {
  Joints position = Joints::Zero(), velocity = Joints::Zero(), acceleration = Joints::Zero(), jerk = Joints::Zero();
};

class FeedPrediction {
 public:
  std::vector<BlockPrediction> blocks;
  double cycle_time = 0;           // s
  double programmed_time = 0;      // s: every block at its programmed feed, rapids and dwells as predicted
  double cutting_length = 0;       // mm of tip travel on feed moves
  double length_at_programmed_feed = 0;  // mm of it at the programmed feed
  // Length (path units) of feed moves held at each axis's limit, per quantity (velocity, acceleration, jerk).
  std::vector<std::array<double, kQuantities>> saturated_length;
  int anchors = 0, iterations = 0;  // the planner's work: zero-acceleration anchors, and its passes

  PathState at_time(double t) const;
  double time_at(double s) const;
  JointState joints_at(const PathState& state) const;
  const MachineProgram& program() const { return program_; }

  // Internal: one double S between two anchors.
  struct Stretch {
    double s0 = 0, t0 = 0;
    DoubleS profile;
    std::size_t first_block = 0, last_block = 0;  // inclusive
  };
  std::vector<Stretch> stretches;
  MachineProgram program_;
  std::vector<BlockPath> paths_;
};

FeedPrediction predict_feed(const MachineProgram& program, const Kinematics& kinematics);

}  // namespace drom::machine
