#pragma once
// Cutter-location data: tool tip and tool axis in the part frame, point by point, with the feed
// (what a CAM system writes before a post-processor). Read from APT CLDATA text (GOTO/x,y,z[,i,j,k],
// FEDRAT/, RAPID, UNITS/, TLAXIS/, with $ continuations and $$ comments) or from a CSV table with
// the columns x, y, z, i, j, k, feed (mm/min; 0 for a rapid). Written as CSV.
#include "machine/kinematics.hpp"
#include "machine/machine_program.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace drom::machine {

struct ClPoint {
  ClPose pose;
  double feed = 0;     // mm/min to reach this point; unused for rapids
  bool rapid = false;  // reached by a rapid move
  int line = 0;        // source line
};

struct ClProgram {
  std::string origin;
  std::vector<ClPoint> points;  // the first is where the tool starts
};

ClProgram read_cl_file(const std::filesystem::path& path);
ClProgram parse_apt_cl(const std::string& text, const std::string& origin);
ClProgram parse_cl_csv(const std::string& text, const std::string& origin);
std::string cl_csv(const ClProgram& program);

// Whether a file holds CL data rather than G-code (by its extension: .apt .cl .cls .aptsource, .csv).
bool is_cl_file(const std::filesystem::path& path);

// The CL program on a machine: inverse kinematics point by point (joints continuous, unwound,
// checked against the strokes), one linear block per CL segment, its programmed duration the tip's
// travel over the feed (or, where the tip stays, the rotary travel in degrees over the feed).
struct ClOnMachine {
  MachineProgram program;
  JointPath joints;  // per CL point, with the violations found
};
ClOnMachine cl_to_machine_program(const ClProgram& cl, const Kinematics& kinematics);

}  // namespace drom::machine
