#pragma once
// `drom machine PROGRAM --machine FILE`: what a process engineer checks before running a program.
// The program (G-code, or CL data through the post-processor's kinematics) on the machine: travel
// and singularities per block, the feed it really reaches, the limiting axis and quantity along the
// path, each axis over time, and the cycle time. Writes, in `out`:
//   feed.csv, feed.png     the predicted feed against arc length, beside the programmed feed
//   axes.csv               each axis's position, velocity, acceleration and jerk over time
//   blocks.csv             per block: line, length, times, caps and limiting axes, what held it
//   saturation.vtp         the tool path coloured by limiting axis and quantity (ParaView)
//   summary.json           cycle time, time at the programmed feed, share of length at it,
//                          saturated length per axis and quantity, travel and singularity findings
#include "machine/feed_prediction.hpp"
#include "machine/program_reader.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>
#include <vector>

namespace drom::machine {

struct ProgramCheckOptions {
  std::filesystem::path program;                  // G-code, or CL data (.apt .cl .cls .csv)
  std::string machine = "vmc_3axis";              // a machine file, or a shipped machine's name
  std::vector<std::string> machine_overrides;     // "key=value", like --set
  std::filesystem::path out = "out/machine";
  ProgramReadOptions read;
  double sample_period = -1;                      // s between axes.csv rows; default the interpolation cycle (at most 200 000 rows)
};

// Writes the outputs and returns the summary. Blocks beyond a stroke are listed in the summary and
// then raised as an InputError naming the first one's line (the command exits 2).
nlohmann::json check_program(const ProgramCheckOptions& options);

}  // namespace drom::machine
