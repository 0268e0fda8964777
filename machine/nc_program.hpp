#pragma once
// An NC program as an interpreter sees it: the moves of the axes X, Y, Z (mm) and A, B, C (deg) in the
// program frame, with their feed semantics, independent of any machine. Both readers produce it:
// drom's fast reader for the plain subset (gcode_reader.hpp) and LinuxCNC's rs274 for the full
// language (rs274_reader.hpp); machine_program.hpp maps it onto a machine's joints.
#include <Eigen/Core>

#include <string>
#include <vector>

namespace drom::machine {

using ProgramAxes = Eigen::Matrix<double, 6, 1>;  // X, Y, Z (mm), A, B, C (deg)
constexpr const char* kProgramAxisLetters = "XYZABC";

enum class MoveType { Rapid, Linear, Arc, Dwell };
enum class FeedMode { UnitsPerMinute, InverseTime };
enum class PathControl { Blend, ExactStop };  // G64 (with an optional P tolerance) / G61, G61.1

struct NcMove {
  MoveType type = MoveType::Linear;
  ProgramAxes start = ProgramAxes::Zero(), end = ProgramAxes::Zero();
  // Arcs: in the plane of `plane` (17: XY, 18: XZ, 19: YZ), about `centre` (its coordinate along the
  // plane's normal is the start's), `rotation` as LinuxCNC counts it: the sign is the direction
  // (+: counter-clockwise seen from the normal's positive side), |rotation| - 1 extra full turns.
  int plane = 17;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  int rotation = 0;
  FeedMode feed_mode = FeedMode::UnitsPerMinute;
  double feed = 0;            // units/min along the feed reference (G94), or 1/min (G93); 0 for rapids and dwells
  double dwell = 0;           // s (Dwell)
  PathControl control = PathControl::Blend;
  double blend_tolerance = -1;  // mm: G64 P; negative: the machine's own
  bool stop_before = false;   // a tool change, program stop or mode change the NC waits at before this move
  int tool_length_offset = 0; // the active G43 H number, 0 without (kept as data: programs are written for the tool tip)
  int line = 0;               // source line (0: unknown, e.g. a move from a subroutine file)

  // The interpreter's feed reference: the XYZ length when X, Y or Z move, else the ABC travel (deg).
  double reference_length() const;
  // The programmed duration of a feed move (s): reference length / feed, or 1/feed in inverse time.
  double programmed_duration() const;
};

struct NcProgram {
  std::string origin;  // the file
  std::vector<NcMove> moves;
  std::string reader;  // "drom" or "rs274"
  // The first motion cuts from an unknown position: it is taken to start at the program origin, as
  // LinuxCNC's interpreter does, and its time from there is not the machine's (reported, not refused).
  bool start_assumed = false;
  bool uses_rotary(int axis) const;  // axis 3, 4, 5: A, B, C
};

// The length of an arc move in XYZ (mm), its helical part included.
double arc_length(const NcMove& move);
// The signed sweep of an arc (rad, counter-clockwise positive), full turns included.
double arc_sweep(const NcMove& move);
// The in-plane coordinate indices (first, second) and the normal index of an arc's plane.
struct PlaneAxes {
  int first = 0, second = 1, normal = 2;
};
PlaneAxes plane_axes(int plane);

}  // namespace drom::machine
