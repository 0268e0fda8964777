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
#include "machine/machine_program.hpp"

#include <nlohmann/json.hpp>

#include <string>
#include <vector>

namespace drom::machine {

struct AxisDemand {
  double ratio = 0;  // demanded / available
  std::string axis;  // its letter, empty when no block demands anything
  int line = 0;      // the program line where the worst ratio is
};

// A block whose end lies beyond an axis's stroke.
struct StrokeExcess {
  std::size_t block = 0;  // index into the program's blocks
  int line = 0;
  int joint = 0;
  double value = 0;  // the joint's value (mm, rad), as the stroke is checked (tip-controlled Z: the gauge line)
  std::string what;  // "file:line: A = ... beyond its stroke [min, max] deg"
};

// A block whose tool axis lies within the machine's singularity cone.
struct SingularPassage {
  int line = 0;
  double distance = 0;  // rad from the singular direction
};

struct ProgramVerdict {
  std::string origin;
  std::vector<StrokeExcess> beyond_strokes;      // block ends beyond a stroke, per axis: the first kKeptExcesses
  std::size_t beyond_stroke_count = 0;           // all of them
  static constexpr std::size_t kKeptExcesses = 1000;
  std::vector<SingularPassage> singular_passages;  // one per line
  AxisDemand velocity, acceleration, jerk;     // the worst over every axis and cutting block
  double cycle_time = 0, programmed_time = 0;  // s (judge_program, on a runnable program)
  double share_at_programmed_feed = 0;         // of the cutting length

  bool runnable() const { return beyond_stroke_count == 0; }
  bool slows_down() const { return velocity.ratio > 1 || acceleration.ratio > 1 || jerk.ratio > 1; }
  nlohmann::json to_json() const;
  // The demand ratios alone, as summary.json's "demand_at_programmed_feed".
  nlohmann::json demand_json() const;
  // One line for the console: "program.ngc on m: ...".
  std::string summary_line() const;
};

// Strokes, singular passages and the demand at the programmed feed of a program already read
// (no feed prediction: drom machine makes its own, with every output it writes).
ProgramVerdict scan_program(const MachineProgram& program, const std::string& origin, const Kinematics& kinematics);

// Reads `text` back (InputError for a program the reader refuses) and judges it on the machine:
// scan_program, then the feed prediction's cycle time when it is runnable.
ProgramVerdict judge_program(const std::string& text, const std::string& origin, const Kinematics& kinematics);

}  // namespace drom::machine
