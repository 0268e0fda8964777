#pragma once
// A machine tool as a machining-process engineer describes it: kinematic chain, pivot offsets, tool
// length handling, axis strokes, per-axis velocity / acceleration / jerk limits, interpolation cycle
// and junction tolerance. Read from a TOML file in cases/machines/ (every key checked; docs/machine.md).
//
// Frames and units. Lengths in mm, angles in radians inside drom (degrees in files and programs),
// time in s. The program frame is the frame of the program's X, Y, Z words (the work offset, G54),
// fixed to the machine; the part frame is fixed to the part and equals the program frame shifted by
// `part_origin` when every rotary axis is at 0. The joints are the program's axis words:
//   - 3-axis and table-table: X, Y, Z of the tool tip (tool length compensated along the fixed spindle, G43);
//   - head-head and table-head: X, Y, Z of the head's pivot (tool length and pivot length carried by the
//     post-processor, since a tilted head cannot be compensated by G43 without RTCP).
// Strokes bound the joint values; for the 3-axis and table-table kinematics the Z stroke bounds the
// gauge line, Z + tool_length, so a longer tool shrinks the reachable tip heights.
#include <Eigen/Core>

#include <array>
#include <string>
#include <vector>

namespace drom::machine {

enum class KinematicChain { ThreeAxis, TableTable, HeadHead, TableHead };
const char* chain_name(KinematicChain chain);

struct AxisLimits {
  char name = 'X';
  bool rotary = false;
  double min = 0, max = 0;       // stroke (mm or rad); ±infinity for a continuous rotary axis
  bool continuous = false;       // rotary axis without end stops (unwound to the nearest turn)
  double velocity = 0;           // mm/s or rad/s
  double acceleration = 0;       // mm/s² or rad/s²
  double jerk = 0;               // mm/s³ or rad/s³
  bool within(double value, double tolerance = 1e-9) const { return value >= min - tolerance && value <= max + tolerance; }
};

// A rotary joint of the chain, as it lies with every rotary axis at 0.
struct RotaryJoint {
  bool on_table = true;                               // carries the part (else: carries the spindle)
  Eigen::Vector3d direction = Eigen::Vector3d::UnitZ();  // unit, positive rotation by the right-hand rule
  Eigen::Vector3d point = Eigen::Vector3d::Zero();       // a point on the axis: program frame (table), or relative to the pivot (head)
};

// Blend: each corner rounded on its own within the tolerance (G642, G64 P). Smooth: the control
// joins consecutive corners into one curvature-continuous curve within the tolerance (a compressor:
// 840D COMPCURV, LinuxCNC's naive-CAM G64 Q). ExactStop: the tool stops at every block end (G61.1).
enum class JunctionMode { Blend, Smooth, ExactStop };

struct Machine {
  std::string name, description, origin;  // origin: the file it came from
  KinematicChain chain = KinematicChain::ThreeAxis;
  // Joints: X, Y, Z, then the rotary axes from the base outward (e.g. A then C for a cradle carrying
  // a rotary table; C then A for a fork head on a C axis). axes.size() == 3 + rotary.size().
  std::vector<AxisLimits> axes;
  std::vector<RotaryJoint> rotary;
  // Controller.
  double interpolation_cycle = 0.002;        // s: the NC's interpolation period (T_ipo)
  JunctionMode junction = JunctionMode::Blend;
  double junction_tolerance = 0.01;          // mm: G642-like per-axis deviation allowed at a block junction (linear axes)
  double junction_tolerance_rotary = 0.01 * 3.14159265358979323846 / 180;  // rad (rotary axes)
  double singularity_cone = 1.0 * 3.14159265358979323846 / 180;            // rad: tool axes this close to the singular direction are reported
  // Head.
  double pivot_length = 0;                   // mm: head machines, from the pivot to the gauge line along the spindle
  // Set-up of the job (overridable with --set setup.tool_length=...).
  double tool_length = 100;                  // mm: gauge line to tool tip
  Eigen::Vector3d part_origin = Eigen::Vector3d::Zero();  // mm, program frame
  // The program Z the spindle retracts to before any other motion and before a rotary axis turns
  // (setup.safe_z): the tool tip's on tip-controlled chains, the pivot's on head chains. Default: the
  // top of the Z stroke less 1 mm.
  double safe_z = 0;

  int joint_count() const { return static_cast<int>(axes.size()); }
  int rotary_count() const { return static_cast<int>(rotary.size()); }
  // The joint index of axis letter `name` (X, Y, Z, A, B, C), or -1 when the machine has no such axis.
  int joint_of(char letter) const;
  std::string rotary_letters() const;  // e.g. "AC"; empty for a 3-axis machine
};

// Reads and checks a machine file; `overrides` are "key=value" like --set. Throws InputError naming
// the file, the line and the key.
Machine read_machine(const std::string& path, const std::vector<std::string>& overrides = {});
Machine parse_machine(const std::string& text, const std::string& origin, const std::vector<std::string>& overrides = {});

// The machines shipped in cases/machines/, compiled into drom: their names (file names without .toml).
std::vector<std::string> shipped_machine_names();
// A machine file's path, or the name of a shipped machine ("ucp710_like").
Machine load_machine(const std::string& path_or_name, const std::vector<std::string>& overrides = {});

}  // namespace drom::machine
