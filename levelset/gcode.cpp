#include "levelset/gcode.hpp"

#include "machine/post_processor.hpp"
#include "machine/program_reader.hpp"
#include "support/input_error.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>

namespace drom::levelset {

namespace {

// A pocket program of more moves than this (arcs split included) is no pocket: ~200 MB of moves.
constexpr std::size_t kMostMoves = 2'000'000;

// The pocket program's moves from machine/'s reader: arcs in the XY plane stay arcs (full turns
// split into circles), arcs in XZ and YZ become chords within 1 µm, rotary axes are refused.
Toolpath to_toolpath(const machine::NcProgram& program) {
  Toolpath path;
  const std::string& origin = program.origin;
  if (program.start_assumed) {
    for (const auto& m : program.moves)
      if (m.type != machine::MoveType::Dwell)
        throw InputError(origin + ":" + std::to_string(m.line) + ": first move must be a G0 to a known position (the material removal starts from it)");
  }
  for (const machine::NcMove& m : program.moves) {
    const std::string where = origin + ":" + std::to_string(m.line) + ": ";
    if (m.type == machine::MoveType::Dwell) continue;
    if (m.start.tail<3>().norm() > 1e-9 || m.end.tail<3>().norm() > 1e-9)
      throw InputError(where + "a 3-axis pocket program moves no rotary axis (A, B, C); time a 5-axis program with drom machine");
    Move base;
    base.source_line = m.line;
    base.tool_length_offset = m.tool_length_offset;
    const double duration = m.programmed_duration();
    if (m.type == machine::MoveType::Rapid) {
      base.kind = MoveKind::Rapid;
      base.start = m.start.head<3>();
      base.end = m.end.head<3>();
      path.moves.push_back(base);
      continue;
    }
    const double feed = duration > 0 ? m.reference_length() / duration : 0;  // mm/s
    base.feed = feed;
    if (m.type == machine::MoveType::Linear) {
      base.kind = MoveKind::Linear;
      base.start = m.start.head<3>();
      base.end = m.end.head<3>();
      path.moves.push_back(base);
      continue;
    }
    const machine::PlaneAxes pl = machine::plane_axes(m.plane);
    const double sweep = machine::arc_sweep(m);
    const double r0 = std::hypot(m.start[pl.first] - m.centre[pl.first], m.start[pl.second] - m.centre[pl.second]);
    const double r1 = std::hypot(m.end[pl.first] - m.centre[pl.first], m.end[pl.second] - m.centre[pl.second]);
    const double a0 = std::atan2(m.start[pl.second] - m.centre[pl.second], m.start[pl.first] - m.centre[pl.first]);
    auto room_for = [&](double count) {
      if (static_cast<double>(path.moves.size()) + count > static_cast<double>(kMostMoves))
        throw InputError(where + "the program's moves (arcs split into turns and chords) pass " + std::to_string(kMostMoves) + ": no pocket program is that long");
    };
    auto point = [&](double f) {
      Eigen::Vector3d p = m.start.head<3>() + f * (m.end.head<3>() - m.start.head<3>());
      const double r = r0 + f * (r1 - r0), a = a0 + f * sweep;
      p[pl.first] = m.centre[pl.first] + r * std::cos(a);
      p[pl.second] = m.centre[pl.second] + r * std::sin(a);
      return p;
    };
    if (m.plane == 17) {
      // One move per full turn, then the rest: Move describes at most one turn.
      const double turn = 2 * M_PI;
      room_for(std::floor(std::abs(sweep) / turn) + 1);
      const int full = static_cast<int>(std::floor(std::abs(sweep) / turn - 1e-9));
      double done = 0;
      for (int k = 0; k <= full; ++k) {
        const double part = k < full ? turn : std::abs(sweep) - full * turn;
        Move arc = base;
        arc.kind = sweep > 0 ? MoveKind::ArcCCW : MoveKind::ArcCW;
        arc.start = point(done / std::abs(sweep));
        done += part;
        arc.end = point(done / std::abs(sweep));
        arc.centre = Eigen::Vector3d(m.centre.x(), m.centre.y(), arc.start.z());
        path.moves.push_back(arc);
      }
      continue;
    }
    // XZ and YZ arcs as chords no farther than 1 µm from the arc.
    const double r = std::max(r0, r1);
    const double step = 2 * std::acos(std::max(-1.0, 1 - 1e-3 / std::max(r, 1e-9)));
    room_for(std::ceil(std::abs(sweep) / step));
    const int n = std::max(1, static_cast<int>(std::ceil(std::abs(sweep) / step)));
    Eigen::Vector3d previous = m.start.head<3>();
    for (int k = 1; k <= n; ++k) {
      Move chord = base;
      chord.kind = MoveKind::Linear;
      chord.start = previous;
      chord.end = k == n ? Eigen::Vector3d(m.end.head<3>()) : point(static_cast<double>(k) / n);
      previous = chord.end;
      path.moves.push_back(chord);
    }
  }
  return path;
}

}  // namespace

Toolpath parse_gcode(const std::string& text, const std::string& origin) { return to_toolpath(machine::parse_program(text, origin)); }

Toolpath read_gcode(const std::string& path) {
  if (!std::filesystem::exists(path)) throw InputError(path + ": cannot open G-code file");
  return to_toolpath(machine::read_program(path));
}

std::string write_gcode(const Toolpath& path, const std::string& title) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(4);
  // No spindle, tool change or retract: this is the record of the path the removal simulated, read
  // back by path.gcode from its first position; the programs to run are posted by machine/.
  out << "%\n(" << machine::comment_text(title) << ")\n(written by drom: mm, absolute, F in mm/min)\n"
      << "(the path drom simulated, not a program to run on a machine: no tool change, spindle or coolant)\nG21 G90 G17\n";
  int n = 10;
  int offset = 0;
  double feed = -1;
  if (!path.moves.empty()) {  // a reader starts from an unknown position: state the first one
    const auto& p = path.moves.front().start;
    out << "N" << n << " G0 X" << p.x() << " Y" << p.y() << " Z" << p.z() << "\n";
    n += 10;
  }
  for (const Move& m : path.moves) {
    out << "N" << n << " ";
    n += 10;
    if (m.tool_length_offset != offset) {
      if (m.tool_length_offset) out << "G43 H" << m.tool_length_offset << " ";
      else out << "G49 ";
      offset = m.tool_length_offset;
    }
    switch (m.kind) {
      case MoveKind::Rapid: out << "G0"; break;
      case MoveKind::Linear: out << "G1"; break;
      case MoveKind::ArcCW: out << "G2"; break;
      case MoveKind::ArcCCW: out << "G3"; break;
    }
    out << " X" << m.end.x() << " Y" << m.end.y() << " Z" << m.end.z();
    if (m.is_arc()) out << " I" << m.centre.x() - m.start.x() << " J" << m.centre.y() - m.start.y();
    if (m.cutting() && std::abs(m.feed - feed) > 1e-12) {
      out << " F" << m.feed * 60.0;
      feed = m.feed;
    }
    out << "\n";
  }
  out << "M30\n%\n";
  return out.str();
}

}  // namespace drom::levelset
