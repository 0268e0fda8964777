#pragma once
// A 3-axis pocket program read by machine/'s reader: drom's fast reader for the plain subset, the
// whole RS274/NGC language through LinuxCNC's rs274 otherwise (machine/program_reader.hpp). Arcs in
// XY stay arcs; arcs in XZ and YZ become chords within 1 µm. Rotary words and a first move that cuts
// from an unknown position are errors naming the line, as is anything the interpreter refuses.
#include "levelset/toolpath.hpp"

#include <string>

namespace drom::levelset {

// Parses a program; `origin` names it in errors. Throws InputError.
Toolpath parse_gcode(const std::string& text, const std::string& origin);
Toolpath read_gcode(const std::string& path);

// Writes a program that reproduces the toolpath (mm, absolute, F in mm/min, arcs with I J).
std::string write_gcode(const Toolpath& path, const std::string& title);

}  // namespace drom::levelset
