#pragma once
// The post-processor: cutter-location data turned into the G-code one machine runs, through its
// inverse kinematics (machine-axis programming, no RTCP). LinuxCNC's dialect, which its rs274 reads
// back to the same moves (tests/machine):
//   - 3-axis: G94 feeds in mm/min, tool length by G43 H;
//   - 5-axis: joints X Y Z and the rotary letters in degrees, cutting moves in inverse time (G93, F
//     per block = 1 / its duration in minutes, the duration being the tip's travel over the CL feed),
//     so the tool tip moves at the programmed feed relative to the part; G43 H on the tip-controlled
//     table-table chain, G49 on head chains whose pivot coordinates already carry the tool length.
// A pose beyond a stroke, or an orientation out of reach, is an InputError naming the CL line.
#include "machine/cl_data.hpp"
#include "machine/kinematics.hpp"
#include "machine/machine_program.hpp"

#include <string>

namespace drom::machine {

enum class Coolant { off, flood, mist };

// What makes a program one a machinist runs as it is (docs/machine.md, "Posted programs"):
//   header   %, title, G21 G90 G17 G40 G94 G54, the junction mode, T M6, G43 H (G49 on head chains),
//            S and M3/M4, M8/M7;
//   start    G0 Z to the safe height first (the tool retracts along its axis on tip-controlled
//            chains), then the rotary axes, then X Y, then down to the first point;
//   rapids   a rapid that turns a rotary axis goes up to the safe height first; one that moves in X
//            or Y crosses at the clearance plane (the program's highest point + clearance) at least;
//   end      M5, M9, M30, %.
struct PostOptions {
  std::string title = "drom";
  int tool = 1;                  // T and H number
  double tool_diameter = 0;      // mm: sets the default spindle speed
  double spindle_speed = 0;      // rev/min; 0: default_spindle_speed(tool_diameter)
  bool counter_clockwise = false;  // M4 instead of M3
  Coolant coolant = Coolant::off;
  double clearance = 10;         // mm above the program's highest point: where rapids cross in X, Y
  double blend_tolerance = -1;   // mm for G64 P; negative: the machine's junction tolerance
};

// The default spindle speed: a cutting speed of 300 m/min (carbide in aluminium alloy) on the tool's
// diameter, rounded to 100 rev/min, within [1 000, 24 000]; 10 000 rev/min when the diameter is unknown.
double default_spindle_speed(double tool_diameter);
// The program's spindle speed: the options' own, or the default.
double spindle_speed(const PostOptions& options);
// The header's lines (from '%' to the spindle and coolant), and the end (M5 M9 M30 %).
std::string program_header(const PostOptions& options, const std::string& modal_line, const std::string& tool_length_line, const std::string& comments = {});
// `text` made fit for a G-code comment: '(' and ')' become '[' and ']', control characters spaces.
std::string comment_text(const std::string& text);
std::string program_end(const PostOptions& options);

std::string post_process(const ClProgram& cl, const Kinematics& kinematics, const PostOptions& options = {});

// A machine program (joints) as G-code in the same dialect.
std::string write_machine_gcode(const MachineProgram& program, const Machine& machine, const PostOptions& options = {});

}  // namespace drom::machine
