#pragma once
// The verdict on a program drom has just posted, read back as a machine would read it (drom's plain
// reader, the one `drom machine` uses): does it stay within the strokes and the reach, where does the
// tool axis pass near the singular direction, how hard does it ask the axes at its programmed feed,
// and what feed and cycle time the machine really reaches (feed_prediction.hpp).
//
// The demand. Along each run of cutting blocks at the programmed feeds: the velocity block by block
// (the joints move linearly over a block), the acceleration and jerk by central differences on the
// joints sampled every ten interpolation cycles; each against the axis's limit. A ratio above 1 means the controller must
// slow the tool below the programmed feed there; the feed prediction says by how much. The ten
// cycles are the scale the NC acts on: a sharp corner at feed v demands about 1.4 v / (10 T_ipo).
#include "machine/kinematics.hpp"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace drom::machine {

struct AxisDemand {
  double ratio = 0;  // demanded / available
  std::string axis;  // its letter, empty when no block demands anything
  int line = 0;      // the program line where the worst ratio is
};

struct ProgramVerdict {
  std::string origin;
  std::vector<std::string> out_of_reach;       // "file:line: ..." per block beyond a stroke (the first 20)
  std::size_t out_of_reach_count = 0;
  std::vector<int> singularity_lines;          // lines whose tool axis is within the machine's singularity cone
  AxisDemand velocity, acceleration, jerk;     // the worst over every axis and cutting block
  double cycle_time = 0, programmed_time = 0;  // s
  double share_at_programmed_feed = 0;         // of the cutting length

  bool runnable() const { return out_of_reach_count == 0; }
  bool slows_down() const { return velocity.ratio > 1 || acceleration.ratio > 1 || jerk.ratio > 1; }
  nlohmann::json to_json() const;
  // One line for the console: "program.ngc on m: ...".
  std::string summary_line() const;
};

// Reads `text` back (InputError for a program the reader refuses) and judges it on the machine.
ProgramVerdict judge_program(const std::string& text, const std::string& origin, const Kinematics& kinematics);

}  // namespace drom::machine
