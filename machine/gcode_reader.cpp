#include "machine/gcode_reader.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <limits>
#include <map>
#include <sstream>

namespace drom::machine {

namespace {

struct Modal {
  int motion = -1;  // 0, 1, 2, 3 (G code)
  int plane = 17;
  bool absolute = true;
  double unit = 1.0;  // mm per program length unit
  FeedMode feed_mode = FeedMode::UnitsPerMinute;
  double feed = 0;  // in the feed mode's units, after unit conversion (mm/min or 1/min)
  PathControl control = PathControl::Blend;
  double blend_tolerance = -1;
  bool exact_stop_every_block = false;  // G61.1
  int tool_length_offset = 0;
};

// A G-code number: [+-] digits [. digits], or [+-] . digits (no exponent, no hexadecimal: "G0X2"
// must not read as G 0x2). Returns the characters used, 0 when there is no number.
std::size_t read_number(const std::string& s, std::size_t i, double& value) {
  const std::size_t start = i;
  if (i < s.size() && (s[i] == '+' || s[i] == '-')) ++i;
  const std::size_t digits_from = i;
  while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i;
  std::size_t digits = i - digits_from;
  if (i < s.size() && s[i] == '.') {
    ++i;
    const std::size_t f = i;
    while (i < s.size() && std::isdigit(static_cast<unsigned char>(s[i]))) ++i;
    digits += i - f;
  }
  if (digits == 0) return 0;
  std::string text = s.substr(start, i - start);
  if (text[0] == '+') text.erase(0, 1);
  const auto r = std::from_chars(text.data(), text.data() + text.size(), value);
  if (r.ec == std::errc::result_out_of_range) value = std::numeric_limits<double>::infinity();  // the caller's bounds refuse it
  else if (r.ec != std::errc()) return 0;
  return i - start;
}

// Beyond any machine: a length, feed or dwell past it is a corrupted program (and squaring it, for an
// arc, must stay finite); codes and registers are whole numbers of a few digits (G with one decimal).
constexpr double kLargest = 1e6;
constexpr int kMostTurns = 10000;  // an arc's P: a helix of more turns is no milling program

std::string g_name(int g10) {
  char buf[16];
  std::snprintf(buf, sizeof buf, "G%g", g10 / 10.0);
  return buf;
}

}  // namespace

void settle_program_start(NcProgram& program) {
  for (NcMove& m : program.moves) {
    if (m.type == MoveType::Dwell) continue;
    if (m.type != MoveType::Rapid) program.start_assumed = true;
    else m.start = m.end;
    break;
  }
}

std::string statement_of(const std::string& raw, const std::string& where) {
  std::string line;
  int depth = 0;
  for (char c : raw) {
    if (c == ';' && depth == 0) break;
    if (c == '(') {
      if (depth > 0) throw InputError(where + "nested '(' in a comment");
      ++depth;
    } else if (c == ')') {
      if (depth == 0) throw InputError(where + "')' without '('");
      --depth;
    } else if (depth == 0) {
      line += c;
    }
  }
  if (depth != 0) throw InputError(where + "unclosed comment '('");
  return line;
}

NcProgram parse_plain_gcode(const std::string& text, const std::string& origin) {
  NcProgram program;
  program.origin = origin;
  program.reader = "drom";
  Modal modal;
  ProgramAxes position = ProgramAxes::Zero();
  bool stop_pending = false;
  // How the program ends, as LinuxCNC's interpreter reads it: at M2 or M30 (what follows is never
  // read), or, when its first line is '%', at the next '%'. A file that just stops is a transfer cut
  // short, and the interpreter refuses it.
  bool opened_with_percent = false, ended = false, anything_before = false;
  std::istringstream in(text);
  std::string raw;
  int line_no = 0;
  while (!ended && std::getline(in, raw)) {
    ++line_no;
    const std::string where = origin + ":" + std::to_string(line_no) + ": ";
    auto outside = [&](const std::string& what) { throw OutsidePlainSubset(where + what + " is outside drom's plain G-code subset"); };
    const std::string line = statement_of(raw, where);
    const auto first = line.find_first_not_of(" \t\r"), last = line.find_last_not_of(" \t\r");
    if (first != std::string::npos && line.substr(first, last - first + 1) == "%") {
      if (opened_with_percent) {  // the closing '%'
        ended = true;
        break;
      }
      if (anything_before) throw InputError(where + "'%' stands only on a program's first line and on its closing line");
      opened_with_percent = true;
      continue;
    }
    anything_before = anything_before || raw.find_first_not_of(" \t\r") != std::string::npos;  // a comment too: LinuxCNC then refuses the '%'
    std::map<char, double> words;
    std::vector<int> g_codes, m_codes;
    std::size_t i = 0;
    while (i < line.size()) {
      const char c = static_cast<char>(std::toupper(static_cast<unsigned char>(line[i])));
      if (c == '%') throw InputError(where + "'%' among a block's words: it stands alone, on a program's first line and on its closing line");
      if (std::isspace(static_cast<unsigned char>(c)) || c == '\r') {
        ++i;
        continue;
      }
      if (c == '/') outside("block delete '/'");
      if (c == '#' || c == '[' || c == 'O') outside(c == 'O' ? std::string("an O-word") : c == '#' ? std::string("a #parameter") : std::string("an [expression]"));
      if (!std::isalpha(static_cast<unsigned char>(c))) {
        // A byte that is not text is no G-code at all (a binary file, a copy cut short).
        const auto u = static_cast<unsigned char>(line[i]);
        if (u < 0x20 || u >= 0x7f) throw InputError(where + "expected a word letter, got '" + printable(std::string(1, line[i])) + "'");
        outside("the character '" + std::string(1, line[i]) + "'");
      }
      ++i;
      while (i < line.size() && std::isspace(static_cast<unsigned char>(line[i]))) ++i;
      if (i < line.size() && (line[i] == '#' || line[i] == '[')) outside("a #parameter or [expression] as a word's value");
      double value = 0;
      const std::size_t used = read_number(line, i, value);
      if (used == 0) throw InputError(where + "word '" + std::string(1, c) + "' has no number");
      const std::string number = line.substr(i, used);
      i += used;
      // A code or register: a whole number (G: one decimal) of a few digits, never cast out of range.
      auto code = [&](double scale, double max) {
        const double v = value * scale;
        if (v < 0 || v > max || std::abs(v - std::round(v)) > 1e-6 * scale)
          throw InputError(where + "word '" + std::string(1, c) + printable(number) + "' is not a code drom knows");
        return static_cast<int>(std::lround(v));
      };
      if (c != 'G' && c != 'M' && c != 'H' && c != 'N' && c != 'T' && c != 'S' && std::abs(value) > kLargest)
        throw InputError(where + "word " + std::string(1, c) + printable(number) + " is beyond any machine (|value| <= 1e6)");
      switch (c) {
        case 'G': g_codes.push_back(code(10, 9999)); break;
        case 'M': m_codes.push_back(code(1, 999)); break;
        case 'N': case 'T': case 'S': break;
        case 'D': outside("a D word (cutter compensation)"); break;
        case 'U': case 'V': case 'W': outside(std::string("the ") + c + " axis"); break;
        case 'L': case 'E': outside(std::string("an ") + c + " word"); break;
        case 'H': case 'X': case 'Y': case 'Z': case 'A': case 'B': case 'C': case 'I': case 'J': case 'K': case 'R': case 'F': case 'P': case 'Q':
          if (words.count(c)) throw InputError(where + "word " + std::string(1, c) + " appears twice");
          words[c] = c == 'H' ? code(1, 99999) : value;
          break;
        default: outside("the word '" + std::string(1, c) + "'");
      }
    }
    bool dwell = false, g43 = false, g64 = false;
    int motion_words = 0;
    for (int g : g_codes) {
      switch (g) {
        case 0: case 10: case 20: case 30: modal.motion = g / 10; ++motion_words; break;
        case 40: dwell = true; break;
        case 170: case 180: case 190: modal.plane = g / 10; break;
        case 200: modal.unit = 25.4; break;
        case 210: modal.unit = 1.0; break;
        case 400: case 540: case 800: case 911: break;  // no cutter compensation, G54, no canned cycle, incremental arc centres
        case 430: g43 = true; break;
        case 490: modal.tool_length_offset = 0; break;
        case 610: modal.control = PathControl::Blend, modal.blend_tolerance = 0, modal.exact_stop_every_block = false; break;
        case 611: modal.control = PathControl::ExactStop, modal.exact_stop_every_block = true; break;
        case 640: g64 = true; break;
        case 900: modal.absolute = true; break;
        case 910: modal.absolute = false; break;
        case 930: modal.feed_mode = FeedMode::InverseTime, modal.feed = 0; break;
        case 940: if (modal.feed_mode != FeedMode::UnitsPerMinute) modal.feed = 0; modal.feed_mode = FeedMode::UnitsPerMinute; break;
        default: outside(g_name(g));
      }
    }
    if (motion_words > 1) throw InputError(where + "two motion words (G0/G1/G2/G3) in one block");
    if (words.count('H') && !g43) throw InputError(where + "H word without G43");
    if (g43) modal.tool_length_offset = words.count('H') ? static_cast<int>(std::lround(words['H'])) : 0;
    if (g64) {
      modal.control = PathControl::Blend;
      modal.exact_stop_every_block = false;
      modal.blend_tolerance = words.count('P') ? words['P'] * modal.unit : -1;
      if (modal.blend_tolerance < -0.5 && words.count('P')) throw InputError(where + "G64 P must not be negative");
    } else if (words.count('Q')) {
      throw InputError(where + "Q word without G64");
    }
    for (int m : m_codes) {
      switch (m) {
        case 2: case 30: ended = true; stop_pending = true; break;            // the program's end: nothing after it is read
        case 0: case 1: case 6: stop_pending = true; break;                   // the NC stops: program stop, tool change
        case 3: case 4: case 5: case 7: case 8: case 9: break;
        default: outside("M" + std::to_string(m));
      }
    }
    if (dwell) {
      if (!words.count('P') || words['P'] < 0) throw InputError(where + "G4 needs P, the dwell in seconds (>= 0)");
      NcMove d;
      d.type = MoveType::Dwell;
      d.start = d.end = position;
      d.dwell = words['P'];
      d.line = line_no;
      program.moves.push_back(d);
      stop_pending = true;
      continue;
    }
    if (words.count('F')) {
      if (!(words['F'] > 0)) throw InputError(where + "F must be positive");
      modal.feed = modal.feed_mode == FeedMode::InverseTime ? words['F'] : words['F'] * modal.unit;
    }
    bool has_axis = false;
    for (char a : std::string("XYZABC")) has_axis = has_axis || words.count(a);
    const bool arc_words = words.count('I') || words.count('J') || words.count('K') || words.count('R');
    if (!has_axis && !(modal.motion >= 2 && arc_words && motion_words)) {
      if (arc_words) throw InputError(where + "arc words without a motion");
      if (words.count('P') && !g64) throw InputError(where + "P word without G4, G64 or an arc");
      continue;
    }
    if (modal.motion < 0) throw InputError(where + "axis words before any motion mode (G0/G1/G2/G3)");
    ProgramAxes target = position;
    for (int k = 0; k < 6; ++k) {
      const char axis = kProgramAxisLetters[k];
      if (!words.count(axis)) continue;
      const double v = words[axis] * (k < 3 ? modal.unit : 1.0);
      target[k] = modal.absolute ? v : position[k] + v;
    }
    NcMove move;
    move.start = position;
    move.end = target;
    move.line = line_no;
    move.control = modal.control;
    move.blend_tolerance = modal.blend_tolerance;
    move.stop_before = stop_pending;
    move.tool_length_offset = modal.tool_length_offset;
    stop_pending = modal.exact_stop_every_block;
    if (modal.motion == 0) {
      move.type = MoveType::Rapid;
    } else {
      if (modal.feed_mode == FeedMode::InverseTime && !words.count('F'))
        throw InputError(where + "inverse-time feed (G93) needs an F word on every cutting move");
      if (modal.feed <= 0) throw InputError(where + "cutting move (G" + std::to_string(modal.motion) + ") without a feed rate: add an F word");
      move.feed = modal.feed;
      move.feed_mode = modal.feed_mode;
      move.type = modal.motion == 1 ? MoveType::Linear : MoveType::Arc;
    }
    if (move.type == MoveType::Arc) {
      const PlaneAxes p = plane_axes(modal.plane);
      move.plane = modal.plane;
      const char offset_word[3] = {'I', 'J', 'K'};
      const char first_word = offset_word[p.first], second_word = offset_word[p.second], normal_word = offset_word[p.normal];
      if (words.count(normal_word))
        throw InputError(where + std::string(1, normal_word) + " is not an arc word of " + g_name(modal.plane * 10) + " (it uses " + first_word + " and " +
                         second_word + ")");
      const int turns = words.count('P') ? static_cast<int>(std::lround(words['P'])) : 1;
      if (words.count('P') && !(words['P'] >= 1 && words['P'] <= kMostTurns && std::abs(words['P'] - std::round(words['P'])) <= 1e-9))
        throw InputError(where + "arc P (turns) must be a whole number from 1 to " + std::to_string(kMostTurns));
      move.rotation = (modal.motion == 3 ? 1 : -1) * turns;
      const Eigen::Vector2d a(position[p.first], position[p.second]), b(target[p.first], target[p.second]);
      Eigen::Vector2d centre;
      if (words.count('R')) {
        if (words.count(first_word) || words.count(second_word)) throw InputError(where + "arc gives both R and a centre");
        const double r = words['R'] * modal.unit, chord = (b - a).norm();
        if (chord < 1e-9) throw InputError(where + "an R-format arc cannot describe a full circle: give its centre");
        if (chord > 2 * std::abs(r) + 1e-6) {
          char buf[160];
          std::snprintf(buf, sizeof buf, "arc radius R %.4f is shorter than half the chord %.4f", std::abs(r), chord / 2);
          throw InputError(where + buf);
        }
        const Eigen::Vector2d mid = 0.5 * (a + b), dir = (b - a) / chord, normal(-dir.y(), dir.x());
        const double offset = std::sqrt(std::max(0.0, r * r - chord * chord / 4));
        // A positive R takes the short way; counter-clockwise turns left about the centre.
        const double side = (modal.motion == 3 ? 1.0 : -1.0) * (r > 0 ? 1.0 : -1.0);
        centre = mid + side * offset * normal;
      } else {
        if (!words.count(first_word) && !words.count(second_word))
          throw InputError(where + "arc without a centre (" + first_word + "/" + second_word + ") or R");
        centre = a + Eigen::Vector2d(words.count(first_word) ? words[first_word] * modal.unit : 0, words.count(second_word) ? words[second_word] * modal.unit : 0);
      }
      const double ra = (a - centre).norm(), rb = (b - centre).norm();
      if (ra < 1e-9) throw InputError(where + "arc centre coincides with its start point");
      if (std::abs(ra - rb) > std::max(2e-3, 1e-4 * ra)) {
        char buf[160];
        std::snprintf(buf, sizeof buf, "arc radius is inconsistent: %.4f mm at the start, %.4f mm at the end", ra, rb);
        throw InputError(where + buf);
      }
      move.centre = position.head<3>();
      move.centre[p.first] = centre.x();
      move.centre[p.second] = centre.y();
    } else if (words.count('I') || words.count('J') || words.count('K') || words.count('R')) {
      throw InputError(where + "arc words on a " + (modal.motion == 0 ? std::string("G0") : std::string("G1")) + " move");
    }
    program.moves.push_back(move);
    position = target;
  }
  if (line_no == 0) throw InputError(origin + ": the file is empty, not a program");
  if (!ended) {
    const std::string where = origin + ":" + std::to_string(line_no) + ": ";
    if (opened_with_percent) throw InputError(where + "the file ends with no closing '%' (it opened with '%'): a transfer cut short? LinuxCNC refuses it too");
    throw InputError(where + "the program has no end (no M2 or M30, and no '%' around it): a transfer cut short? LinuxCNC refuses it too");
  }
  settle_program_start(program);
  return program;
}

}  // namespace drom::machine
