#pragma once
// drom's own G-code reader: the plain subset that CAM posts and drom's post-processor write, read
// fast and with drom's own error messages.
//   G0 G1 G2 G3 (I J K, or R; P turns) in G17 / G18 / G19, G4 P dwell, G20 G21, G90 G91, G91.1,
//   G93 G94 (F per move in inverse time), G61 (exact path) G61.1 (exact stop) G64 [P tolerance],
//   G43 Hn / G49 (kept as data: the program is taken to be written for the tool tip), G40 G54 G80,
//   axis words X Y Z A B C, N, F, S, T, M0 M1 M2 M3 M4 M5 M6 M7 M8 M9 M30, ( ) and ; comments, %.
// Anything outside it that is still G-code (O-words, #parameters, [expressions], canned cycles,
// cutter compensation, G28/G30/G53/G92, other work offsets, block delete, ...) raises
// OutsidePlainSubset, and program_reader.hpp hands the program to LinuxCNC's interpreter instead.
// Real mistakes in the plain subset (a cutting move without a feed, an inconsistent arc, a word
// given twice) raise InputError naming the line.
#include "machine/nc_program.hpp"
#include "support/input_error.hpp"

#include <string>

namespace drom::machine {

class OutsidePlainSubset : public InputError {
 public:
  using InputError::InputError;
};

NcProgram parse_plain_gcode(const std::string& text, const std::string& origin);

// One line's statement, its comments cut out ('(...)' and all from ';'). Throws InputError naming
// `where` ("file:line: ") for a '(' inside a comment, a ')' without '(' or a comment left open, as
// LinuxCNC's interpreter refuses them.
std::string statement_of(const std::string& line, const std::string& where);

// The convention both readers share: a program starts where its first motion ends when that is a
// rapid (the machine's position before it is unknown); a first motion that cuts starts at the program
// origin, as LinuxCNC's interpreter assumes, and the program says so (start_assumed).
void settle_program_start(NcProgram& program);

}  // namespace drom::machine
