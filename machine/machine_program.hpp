#pragma once
// A program as one machine runs it: blocks between joint configurations (machine order, mm and rad),
// with their programmed durations. Made from an NC program (whose axis words must exist on the
// machine) or from cutter-location data through the inverse kinematics.
#include "machine/kinematics.hpp"
#include "machine/nc_program.hpp"

#include <string>
#include <vector>

namespace drom::machine {

struct MachineBlock {
  MoveType type = MoveType::Linear;
  Joints start = Joints::Zero(), end = Joints::Zero();
  // Arcs move X, Y, Z on a circle (program frame), rotary joints linearly along it.
  int plane = 17;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  int rotation = 0;
  double programmed_duration = 0;  // s: feed moves at their programmed feed, dwells; 0 for rapids
  double blend_tolerance = -1;     // mm; negative: the machine's own
  bool stop_before = false;        // the NC stops at the start of this block
  int line = 0;                    // source line (program or CL file), 0 when unknown
};

struct MachineProgram {
  std::string origin;
  std::vector<MachineBlock> blocks;
};

// Throws InputError (file:line) when the program moves an axis the machine lacks.
MachineProgram to_machine_program(const NcProgram& program, const Machine& machine);

// The joints' position on a block at the fraction sigma in [0, 1] of it (the NC interpolates lines
// and rotary axes linearly in the joints, arcs on their circle).
Joints block_joints_at(const MachineBlock& block, double sigma);

// A block as a path: its length in the path coordinate s and the joints' derivatives along it.
// s is the tool tip's travel in the part frame (the chord between the block's ends through the
// forward kinematics, the arc length on arcs), or, on a block where the tip stays put and only
// rotary axes turn, their travel in degrees (LinuxCNC's feed reference for such moves).
struct BlockPath {
  double length = 0;
  bool rotary_only = false;
  Joints rate_start = Joints::Zero(), rate_end = Joints::Zero();  // dq/ds at the ends
  Joints rate_max = Joints::Zero();                               // max |dq/ds| over the block
  double arc_radius = 0;   // arcs: the radius (mm), and the in-plane share of |dq/ds| (R |sweep| / ℓ)
  double arc_in_plane = 0;
  struct Derivatives {
    Joints q = Joints::Zero(), d1 = Joints::Zero(), d2 = Joints::Zero(), d3 = Joints::Zero();  // d^n q / ds^n
  };
  Derivatives at(const MachineBlock& block, double sigma) const;
};
BlockPath block_path(const MachineBlock& block, const Kinematics& kinematics);

}  // namespace drom::machine
