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

struct PostOptions {
  std::string title = "drom";
  int tool = 1;                 // T and H number
  double spindle_speed = 0;     // rev/min; 0: no S word nor M3
  double blend_tolerance = -1;  // mm for G64 P; negative: the machine's junction tolerance
};

std::string post_process(const ClProgram& cl, const Kinematics& kinematics, const PostOptions& options = {});

// A machine program (joints) as G-code in the same dialect.
std::string write_machine_gcode(const MachineProgram& program, const Machine& machine, const PostOptions& options = {});

}  // namespace drom::machine
