#pragma once
// The full RS274/NGC language (O-word subroutines and loops, #parameters and expressions, canned
// cycles, cutter compensation, G28/G30/G53/G92, work offsets, ...) read by LinuxCNC's own
// interpreter: its standalone `rs274` (Debian's linuxcnc-uspace) runs the program and prints its
// canonical machining functions (STRAIGHT_TRAVERSE, STRAIGHT_FEED, ARC_FEED, DWELL, ...), which are
// read back into an NcProgram. drom does not interpret the language itself.
//
// Each line of a copy of the program is given an N word holding its line number, so every move and
// every error names its source line. Offsets (G5x, G92) are added to the canonical coordinates: the
// program's X, Y, Z are those of the G54 frame with LinuxCNC's offsets all zero at the start.
// rs274 reads a tool table in inches: drom writes one whose tools have the diameters given (or 0,
// which makes cutter compensation a no-op; the program summary says so).
#include "machine/nc_program.hpp"

#include <chrono>
#include <filesystem>
#include <map>
#include <string>
#include <string_view>
#include <vector>

namespace drom::machine {

struct Rs274Options {
  std::map<int, double> tool_diameters;                    // mm, by tool number; others are 0
  std::vector<std::filesystem::path> subroutine_paths;     // searched for O<name> call (the program's folder is always)
  std::chrono::seconds timeout{120};                       // an endless O-word loop is stopped and reported
  std::string executable;                                  // empty: $DROM_RS274, else rs274 on the PATH
};

// Whether LinuxCNC's interpreter can be run here.
bool rs274_available(const Rs274Options& options = {});

// Throws InputError with the file, the line and the interpreter's message when it refuses the program.
// The two steps below, composed.
NcProgram read_with_rs274(const std::filesystem::path& program, const Rs274Options& options = {});

// Step 1: the interpreter run on the program: its canonical calls (stdout and stderr) and its exit
// status. Throws InputError when the program cannot be read, rs274 is missing or does not finish.
struct Rs274Run {
  std::string calls;
  int status = 0;
};
Rs274Run run_rs274(const std::filesystem::path& program, const Rs274Options& options = {});

// Step 2: the canonical calls read into moves, with `origin` (the program's name) in every message;
// a non-zero status becomes the interpreter's complaint, named by the program line. Separate so that
// drom's side of the exchange can be fuzzed without a process per input (fuzz/rs274_calls.cpp).
NcProgram parse_rs274_calls(std::string_view calls, int status, const std::string& origin);

}  // namespace drom::machine
