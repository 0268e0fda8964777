#pragma once
// The `[program]` table every case that posts a program reads (drom finish, drom orient, drom copy):
// what the post-processor writes into the program's header and how it moves between cuts
// (machine/post_processor.hpp; docs/case-files.md, "[program]"):
//   tool_number    T and H (1 ... 999)
//   spindle_speed  rev/min; 0: the default for the tool's diameter (default_spindle_speed)
//   spindle        "cw" (M3) or "ccw" (M4)
//   coolant        "off", "flood" (M8) or "mist" (M7)
//   clearance      mm above the program's highest point: the plane rapids cross in X and Y
#include "machine/post_processor.hpp"
#include "support/toml_reader.hpp"

namespace drom::machine {

// `defaults` carries the command's own title, tool number and diameter; the keys override them.
PostOptions read_program_keys(TomlReader& reader, PostOptions defaults);

}  // namespace drom::machine
