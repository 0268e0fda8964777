#include "levelset/gcode.hpp"

#include "support/input_error.hpp"

#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <map>
#include <sstream>

namespace drom::levelset {

namespace {

constexpr double kLargest = 1e6;

struct Modal {
  int motion = -1;  // 0, 1, 2, 3
  bool absolute = true;
  double unit = 1.0;  // mm per program unit
  double feed = 0;    // mm/s, 0 until an F word
  int tool_length_offset = 0;
};

}  // namespace

Toolpath parse_gcode(const std::string& text, const std::string& origin) {
  Toolpath path;
  Modal modal;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
  bool position_known = false;
  std::istringstream in(text);
  std::string raw;
  int line_no = 0;
  while (std::getline(in, raw)) {
    ++line_no;
    const std::string where = origin + ":" + std::to_string(line_no) + ": ";
    // Strip comments.
    std::string line;
    int depth = 0;
    for (char c : raw) {
      if (c == ';' && depth == 0) break;
      if (c == '(') ++depth;
      else if (c == ')') {
        if (depth == 0) throw InputError(where + "')' without '('");
        --depth;
      } else if (depth == 0) line += c;
    }
    if (depth != 0) throw InputError(where + "unclosed comment '('");
    std::map<char, double> words;
    std::vector<int> g_codes;
    bool h_seen = false;
    std::size_t i = 0;
    while (i < line.size()) {
      const char c = static_cast<char>(std::toupper(static_cast<unsigned char>(line[i])));
      if (std::isspace(static_cast<unsigned char>(c)) || c == '%') {
        ++i;
        continue;
      }
      if (!std::isalpha(static_cast<unsigned char>(c))) throw InputError(where + "expected a word letter, got '" + printable(std::string(1, line[i])) + "'");
      ++i;
      while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
      // The number in place (no copy of the rest of the line: a long line would cost its square).
      // Only a plain decimal: strtod's "inf", "nan" and hexadecimal forms are no G-code.
      const char* begin = line.c_str() + i;
      char* end = nullptr;
      const double value = std::strtod(begin, &end);
      const std::string number(begin, static_cast<std::size_t>(end - begin));
      if (end == begin) throw InputError(where + "word '" + std::string(1, c) + "' has no number");
      if (!std::isfinite(value) || number.find_first_not_of("+-.0123456789eE") != std::string::npos)
        throw InputError(where + "word '" + std::string(1, c) + "' has '" + number + "', not a finite decimal number");
      i += static_cast<std::size_t>(end - begin);
      // Words that name a code or a register take whole numbers of a few digits (G one decimal).
      auto code = [&](double scale, double max) {
        const double v = value * scale;
        if (v < 0 || v > max || std::abs(v - std::round(v)) > 1e-6 * scale)
          throw InputError(where + "word '" + std::string(1, c) + number + "' is not a code drom knows");
        return static_cast<int>(std::lround(v));
      };
      switch (c) {
        case 'G': g_codes.push_back(code(10, 9999)); break;
        case 'N': case 'T': case 'S': break;
        case 'M': {
          const int m = code(1, 999);
          if (m != 0 && m != 1 && m != 2 && m != 3 && m != 4 && m != 5 && m != 6 && m != 8 && m != 9 && m != 30)
            throw InputError(where + "unsupported word M" + std::to_string(m));
          break;
        }
        case 'H': modal.tool_length_offset = code(1, 99999); h_seen = true; break;
        case 'X': case 'Y': case 'Z': case 'I': case 'J': case 'K': case 'R': case 'F':
          if (words.count(c)) throw InputError(where + "word " + std::string(1, c) + " appears twice");
          // A kilometre (or 10^6 mm/min) is beyond any machine: such a number is a corrupted program,
          // and squaring it (arcs) must stay finite.
          if (std::abs(value) > kLargest) throw InputError(where + "word " + std::string(1, c) + number + " is beyond any machine (|value| <= 1e6)");
          words[c] = value;
          break;
        default: throw InputError(where + "unsupported word '" + std::string(1, c) + "'");
      }
    }
    bool g43 = false;
    for (int g : g_codes) {
      switch (g) {
        case 0: case 10: case 20: case 30: modal.motion = g / 10; break;
        case 170: case 400: case 800: case 940: case 540: break;  // XY plane, no cutter comp, no canned cycle, feed/min, G54
        case 180: case 190: throw InputError(where + "only G17 (XY-plane) arcs are supported, found G" + std::to_string(g / 10));
        case 200: modal.unit = 25.4; break;
        case 210: modal.unit = 1.0; break;
        case 900: modal.absolute = true; break;
        case 910: modal.absolute = false; break;
        case 430: g43 = true; break;
        case 490: modal.tool_length_offset = 0; break;
        default: {
          char buf[32];
          std::snprintf(buf, sizeof buf, "G%g", g / 10.0);
          throw InputError(where + "unsupported word " + buf);
        }
      }
    }
    if (h_seen && !g43) throw InputError(where + "H word without G43");
    if (words.count('F')) {
      if (!(words['F'] > 0)) throw InputError(where + "F must be positive");
      modal.feed = words['F'] * modal.unit / 60.0;  // units/min -> mm/s
    }
    const bool has_axis = words.count('X') || words.count('Y') || words.count('Z');
    if (!has_axis) {
      if (words.count('I') || words.count('J') || words.count('R')) throw InputError(where + "arc words without an end point");
      continue;
    }
    if (modal.motion < 0) throw InputError(where + "axis words before any motion mode (G0/G1/G2/G3)");
    Eigen::Vector3d target = position;
    for (int k = 0; k < 3; ++k) {
      const char axis = static_cast<char>('X' + k);
      if (!words.count(axis)) continue;
      const double v = words[axis] * modal.unit;
      target[k] = modal.absolute ? v : position[k] + v;
    }
    if (!position_known && modal.motion != 0) throw InputError(where + "first move must be a G0 to a known position");
    Move move;
    move.start = position;
    move.end = target;
    move.source_line = line_no;
    move.tool_length_offset = modal.tool_length_offset;
    if (modal.motion == 0) {
      move.kind = MoveKind::Rapid;
      if (!position_known) move.start = target;  // the machine's position before the first move is unknown
    } else {
      if (modal.feed <= 0) throw InputError(where + "cutting move (G" + std::to_string(modal.motion) + ") without a feed rate: add an F word");
      move.feed = modal.feed;
      move.kind = modal.motion == 1 ? MoveKind::Linear : (modal.motion == 2 ? MoveKind::ArcCW : MoveKind::ArcCCW);
    }
    if (move.is_arc()) {
      if (words.count('K')) throw InputError(where + "K is not an XY-plane arc word (G17 uses I and J)");
      const Eigen::Vector2d a = position.head<2>(), b = target.head<2>();
      if (words.count('R')) {
        if (words.count('I') || words.count('J')) throw InputError(where + "arc gives both R and I/J");
        const double r = words['R'] * modal.unit, chord = (b - a).norm();
        if (chord < 1e-9) throw InputError(where + "R-format arc cannot describe a full circle");
        if (chord > 2 * std::abs(r) + 1e-6) throw InputError(where + "arc radius R " + std::to_string(std::abs(r)) + " is shorter than half the chord " + std::to_string(chord / 2));
        const Eigen::Vector2d mid = 0.5 * (a + b), dir = (b - a) / chord, normal(-dir.y(), dir.x());
        const double offset = std::sqrt(std::max(0.0, r * r - chord * chord / 4));
        // Positive R takes the short way; CCW turns left around the centre.
        const double side = (move.kind == MoveKind::ArcCCW ? 1.0 : -1.0) * (r > 0 ? 1.0 : -1.0);
        move.centre.head<2>() = mid + side * offset * normal;
      } else {
        if (!words.count('I') && !words.count('J')) throw InputError(where + "arc without I/J or R");
        move.centre.head<2>() = a + Eigen::Vector2d(words.count('I') ? words['I'] * modal.unit : 0, words.count('J') ? words['J'] * modal.unit : 0);
      }
      const double ra = (a - move.centre.head<2>()).norm(), rb = (b - move.centre.head<2>()).norm();
      if (ra < 1e-9) throw InputError(where + "arc centre coincides with its start point");
      if (std::abs(ra - rb) > std::max(2e-3, 1e-4 * ra)) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "arc radius is inconsistent: %.4f mm at the start, %.4f mm at the end", ra, rb);
        throw InputError(where + buf);
      }
      move.centre.z() = position.z();
    }
    path.moves.push_back(move);
    position = target;
    position_known = true;
  }
  return path;
}

Toolpath read_gcode(const std::string& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path + ": cannot open G-code file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return parse_gcode(ss.str(), path);
}

std::string write_gcode(const Toolpath& path, const std::string& title) {
  std::ostringstream out;
  out.setf(std::ios::fixed);
  out.precision(4);
  out << "%\n(" << title << ")\n(written by drom: mm, absolute, F in mm/min)\nG21 G90 G17\n";
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
