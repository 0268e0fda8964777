#pragma once
// Issue 44, check 2: a program a machinist runs as it is. Read from its text alone, by code that
// shares nothing with drom's writers or readers (a word scanner of its own):
//   - it opens with '%' and states units, plane and work offset (G21, G17, G54) before any move;
//   - the tool is changed (T M6) and the spindle started (S and M3 or M4) before the first cut;
//   - its first move is a G0 in Z alone (a retract), before any X, Y or rotary motion;
//   - a G0 that turns a rotary axis does so at the height of that first retract (the safe height);
//   - a G0 that moves X or Y does so above every point the program cuts;
//   - it ends with M5, M30 and '%';
// and LinuxCNC's interpreter reads it to the moves drom's reader sees (when rs274 is installed).
#include "machine/program_reader.hpp"
#include "machine/rs274_reader.hpp"
#include "same_moves.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <map>
#include <sstream>
#include <string>
#include <vector>

namespace shop_safe {

struct Block {
  int line = 0;
  std::map<char, std::vector<double>> words;  // letter -> values in the block
  bool has(char c, double v) const {
    const auto it = words.find(c);
    return it != words.end() && std::any_of(it->second.begin(), it->second.end(), [&](double x) { return std::abs(x - v) < 1e-9; });
  }
  bool has(char c) const { return words.count(c) > 0; }
};

inline std::vector<Block> blocks_of(const std::string& text, std::vector<std::string>& lines) {
  std::vector<Block> blocks;
  std::istringstream in(text);
  std::string raw;
  int n = 0;
  while (std::getline(in, raw)) {
    ++n;
    lines.push_back(raw);
    std::string s;
    int depth = 0;
    for (char c : raw) {
      if (c == ';' && depth == 0) break;
      if (c == '(') ++depth;
      else if (c == ')') --depth;
      else if (depth == 0) s += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    }
    Block b;
    b.line = n;
    for (std::size_t i = 0; i < s.size();) {
      if (!std::isalpha(static_cast<unsigned char>(s[i]))) {
        ++i;
        continue;
      }
      const char letter = s[i++];
      char* end = nullptr;
      const double v = std::strtod(s.c_str() + i, &end);
      i = static_cast<std::size_t>(end - s.c_str());
      b.words[letter].push_back(v);
    }
    if (!b.words.empty()) blocks.push_back(b);
  }
  return blocks;
}

inline void expect_shop_safe(const std::string& text, const std::string& what) {
  SCOPED_TRACE(what);
  std::vector<std::string> lines;
  const std::vector<Block> blocks = blocks_of(text, lines);
  ASSERT_FALSE(lines.empty());
  EXPECT_EQ(lines.front(), "%");
  // Modal state, as a reader of the text follows it.
  int motion = -1;
  std::map<char, double> at;
  bool units = false, plane = false, offset = false, tool = false, spindle = false, ended = false, moved = false;
  double safe = std::numeric_limits<double>::quiet_NaN();
  struct Rapid {
    int line;
    bool xy, rotary;
    double z;
  };
  std::vector<Rapid> rapids;
  double highest_cut = -std::numeric_limits<double>::infinity();
  int last_cut_line = 0;
  bool spindle_stopped_after_cuts = false;
  for (const Block& b : blocks) {
    units = units || b.has('G', 21);
    plane = plane || b.has('G', 17);
    offset = offset || b.has('G', 54);
    tool = tool || (b.has('T') && b.has('M', 6));
    if (b.has('S') && (b.has('M', 3) || b.has('M', 4))) spindle = true;
    if (b.has('M', 5) && moved) spindle_stopped_after_cuts = true;
    if (b.has('M', 30) || b.has('M', 2)) ended = true;
    for (const double g : b.words.count('G') ? b.words.at('G') : std::vector<double>{})
      if (g == 0 || g == 1 || g == 2 || g == 3) motion = static_cast<int>(g);
    const bool xy = b.has('X') || b.has('Y'), z = b.has('Z'), rotary = b.has('A') || b.has('B') || b.has('C');
    if (!(xy || z || rotary)) continue;
    for (const char c : {'X', 'Y', 'Z', 'A', 'B', 'C'})
      if (b.has(c)) at[c] = b.words.at(c).back();
    if (!moved) {
      EXPECT_TRUE(units && plane && offset) << "line " << b.line << ": a move before G21, G17 and G54";
      EXPECT_TRUE(tool) << "line " << b.line << ": a move before the tool change";
      EXPECT_EQ(motion, 0) << "line " << b.line << ": the first move is not a rapid";
      EXPECT_TRUE(z && !xy && !rotary) << "line " << b.line << ": the first move is not a retract in Z alone: " << lines[static_cast<std::size_t>(b.line - 1)];
      safe = at['Z'];
      moved = true;
      continue;
    }
    if (motion == 0) {
      rapids.push_back({b.line, xy, rotary, at['Z']});
    } else {
      EXPECT_TRUE(spindle) << "line " << b.line << ": cuts before the spindle starts";
      highest_cut = std::max(highest_cut, at['Z']);
      last_cut_line = b.line;
    }
  }
  EXPECT_TRUE(moved) << "no move at all";
  for (const Rapid& r : rapids) {
    if (r.rotary) {
      EXPECT_NEAR(r.z, safe, 1e-6) << "line " << r.line << ": a rotary axis turns off the safe height " << safe;
    }
    if (r.xy) {
      EXPECT_GT(r.z, highest_cut) << "line " << r.line << ": a rapid in X/Y at Z " << r.z << ", below the highest cut " << highest_cut;
    }
  }
  EXPECT_GT(last_cut_line, 0) << "nothing is cut";
  EXPECT_TRUE(spindle_stopped_after_cuts) << "no M5 after the cuts";
  EXPECT_TRUE(ended) << "no M30";
  std::size_t last = lines.size();
  while (last > 0 && lines[last - 1].empty()) --last;
  ASSERT_GE(last, 2u);
  EXPECT_EQ(lines[last - 1], "%");
  EXPECT_EQ(lines[last - 2], "M30");
  // LinuxCNC's interpreter reads the same moves as drom's reader.
  if (drom::machine::rs274_available()) {
    using drom::machine::ReaderChoice;
    expect_same_moves(drom::machine::parse_program(text, what, {ReaderChoice::Plain, {}}), drom::machine::parse_program(text, what, {ReaderChoice::Rs274, {}}));
  }
}

}  // namespace shop_safe
