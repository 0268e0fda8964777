#pragma once
// Inverse and forward kinematics of a machine (3-axis, table-table, head-head, table-head), between
// cutter-location data in the part frame (tool tip x, y, z and tool axis i, j, k, unit, pointing from
// the tip to the spindle) and the joints (X, Y, Z and the rotary axes, machine_definition.hpp).
//
// The tool axis fixes the two rotary angles through R_table(θ) u = R_head(θ) e_z, one instance of
// Paden-Kahan's second subproblem, R(k1, θ1) R(k2, θ2) v = w, solved in closed form: two branches,
// or none when the orientation is out of the chain's reach. It degenerates where v lies along k2 or
// w along k1: there one angle is free (the table-table machine's C when the tool axis lies along C's
// axis), which is the singularity; the free angle then keeps its previous value. Positions follow
// from the product of exponentials of the rotary joints about their lines.
#include "machine/machine_definition.hpp"

#include <Eigen/Core>

#include <array>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace drom::machine {

constexpr int kMaxJoints = 5;
using Joints = Eigen::Matrix<double, kMaxJoints, 1>;  // X, Y, Z, rotary 1, rotary 2 (machine order; unused: 0)

struct ClPose {
  Eigen::Vector3d tip = Eigen::Vector3d::Zero();        // part frame, mm
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();      // part frame, unit, tip -> spindle
};

// The subproblem's two solutions for one pose, before any trigonometry: c = R(k2, θ2) v, one per
// branch. Along a path the branch whose c moves least is the continuous one.
struct BranchSplit {
  int count = 0;  // 0: out of reach; 1: the branches meet; 2
  bool singular = false;
  std::array<Eigen::Vector3d, 2> c;
};

// Both branches of one pose, rotary angles in (-π, π] before unwrapping.
struct IkBranches {
  int count = 0;                 // 0 (orientation unreachable), 1 (singular: the branches coincide) or 2
  std::array<Joints, 2> joints;
  bool singular = false;         // exactly at the singularity: one angle was free
};

class Kinematics {
 public:
  explicit Kinematics(const Machine& machine);
  const Machine& machine() const { return machine_; }

  ClPose forward(const Joints& q) const;
  // `free_angle`: the value the free angle takes at an exact singularity (the previous pose's).
  IkBranches inverse(const ClPose& pose, double free_angle = 0) const;
  // The same in two steps, so a path pays the trigonometry of the branch it takes only.
  BranchSplit split(const ClPose& pose) const;
  Joints solve_branch(const ClPose& pose, const BranchSplit& split, int branch) const;  // not at a singularity
  // The angle between the tool axis (part frame) and the nearest singular direction (π/2 for a 3-axis machine).
  double singularity_distance(const Eigen::Vector3d& axis) const;
  // The part-frame direction that tool axis is measured from (either sign), or none: a 3-axis machine,
  // or a chain singular at every pose.
  std::optional<Eigen::Vector3d> singular_direction() const;
  // The value checked against joint j's stroke: the joint, or for the tip-controlled chains (3-axis,
  // table-table) Z + tool length, the gauge line.
  double stroke_value(int j, const Joints& q) const;
  bool tip_controlled() const { return tip_controlled_; }

  // A rotary joint's turn: its angle, and the cosine and sine it was read from.
  struct Turn {
    double angle = 0, c = 1, s = 0;
  };

 private:
  Joints joints_from_turns(const ClPose& pose, const Turn& first, const Turn& second) const;
  Machine machine_;
  bool tip_controlled_ = true;
  // The subproblem's layout for this chain: which of u (part-frame tool axis) and e_z plays v and w.
  Eigen::Vector3d k1_, k2_, k1xk2_;
  double k1k2_ = 0, cross_norm2_ = 1;
  bool v_is_tool_axis_ = true;  // else w is
  std::vector<int> table_joints_, head_joints_;  // joint indices, base outward
};

// A path's joints, one branch chosen per pose: continuous from pose to pose, rotary axes unwound to
// the nearest turn within their strokes, every stroke checked.
struct JointPath {
  std::vector<Joints> joints;
  std::vector<int> branch;                 // 0 or 1 per pose
  std::vector<double> singularity_distance;  // rad, per pose
  struct Violation {
    std::size_t pose = 0;
    int joint = -1;      // -1: the orientation itself is out of reach
    double value = 0;    // mm or rad (the checked value: for Z possibly the gauge line)
    std::string what;    // human-readable: "A = 131.2 deg beyond its stroke [-100, 120] deg"
  };
  std::vector<Violation> violations;
};

// `start` (optional): the joints before the first pose (continuity from there). Poses are solved in
// parallel, branches chosen in order.
JointPath inverse_path(const Kinematics& kin, std::span<const ClPose> poses, const Joints* start = nullptr);

// Degrees for rotary joints, mm for linear ones, as written in a program.
double joint_in_program_units(const Machine& m, int j, double value);
std::string describe_joint_value(const Machine& m, int j, double value);

}  // namespace drom::machine
