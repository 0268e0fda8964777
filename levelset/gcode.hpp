#pragma once
// ISO 6983 G-code, the subset 3-axis pocketing needs: G0/G1/G2/G3 in G17, G90/G91, G20/G21, F,
// N line numbers, ( ) and ; comments, G43 Hn / G49 tool length offsets (kept as data), and the
// harmless T, S, M words. Anything else is an error naming the line.
#include "levelset/toolpath.hpp"

#include <string>

namespace drom::levelset {

// Parses a program; `origin` names it in errors. Throws InputError.
Toolpath parse_gcode(const std::string& text, const std::string& origin);
Toolpath read_gcode(const std::string& path);

// Writes a program that reproduces the toolpath (mm, absolute, F in mm/min, arcs with I J).
std::string write_gcode(const Toolpath& path, const std::string& title);

}  // namespace drom::levelset
