// Issue 3 check 5: bad G-code is rejected with its line; good G-code round-trips.
#include "levelset/gcode.hpp"
#include "machine/program_reader.hpp"
#include "machine/rs274_reader.hpp"
#include "tests/machine/same_moves.hpp"
#include "support/input_error.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace drom::levelset;

namespace {
std::string error_of(const std::string& program) {
  try {
    parse_gcode(program, "prog.nc");
  } catch (const drom::InputError& e) {
    return e.what();
  }
  return "";
}
}  // namespace

TEST(GCode, ParsesTheSupportedSubset) {
  const auto path = parse_gcode(
      "%\n(pocket)\nN10 G21 G90 G17\nN20 G0 X0 Y0 Z5\nN30 G43 H3 G1 Z-1 F600 ; plunge\nN40 X10\nN50 G2 X20 Y0 I5 J0\n"
      "N60 G91 G1 Y5\nN70 G90 G3 X10 Y5 R5\nN80 G20 G1 X1\nN90 G49 G0 Z0.5\nM30\n",
      "prog.nc");
  ASSERT_EQ(path.moves.size(), 8u);
  EXPECT_EQ(path.moves[1].kind, MoveKind::Linear);
  EXPECT_NEAR(path.moves[1].feed, 10.0, 1e-12);  // F600 mm/min
  EXPECT_EQ(path.moves[1].tool_length_offset, 3);
  EXPECT_EQ(path.moves[3].kind, MoveKind::ArcCW);
  EXPECT_NEAR(path.moves[3].length(), M_PI * 5, 1e-9);
  EXPECT_NEAR(path.moves[4].end.y(), 5, 1e-12);  // incremental
  EXPECT_EQ(path.moves[5].kind, MoveKind::ArcCCW);
  EXPECT_NEAR(path.moves[6].end.x(), 25.4, 1e-12);  // inches
  EXPECT_NEAR(path.moves[7].end.z(), 0.5 * 25.4, 1e-12);
  EXPECT_EQ(path.moves[7].tool_length_offset, 0);
  EXPECT_EQ(path.moves[2].source_line, 6);
}

TEST(GCode, RejectsBadProgramsNamingTheLine) {
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nG1 X5 Q3 F100\n").find("prog.nc:2: Q word without G64"), std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nG1 X5\n").find("prog.nc:2: cutting move (G1) without a feed rate"), std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nG2 X10 Y0 I4 J0 F100\n").find("prog.nc:2: arc radius is inconsistent: 4.0000 mm at the start, 6.0000 mm at the end"),
            std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nG1 X10 A30 F100\nM2\n").find("prog.nc:2: a 3-axis pocket program moves no rotary axis"), std::string::npos);
  EXPECT_NE(error_of("G21\nG1 X10 F100\nM2\n").find("prog.nc:2: first move must be a G0"), std::string::npos);
  EXPECT_NE(error_of("G0 X0 Y0 Z0\nG2 X10 Y0 R2 F100\n").find("prog.nc:2: arc radius R"), std::string::npos);
  EXPECT_NE(error_of("X1 Y2\n").find("prog.nc:1: axis words before any motion mode"), std::string::npos);
  EXPECT_NE(error_of("G0 X0 (unclosed\n").find("prog.nc:1: unclosed comment"), std::string::npos);
  EXPECT_NE(error_of("G0 X0 X1\n").find("prog.nc:1: word X appears twice"), std::string::npos);
  // Outside the plain subset, LinuxCNC's interpreter reads the program and names the line it refuses.
  const std::string cycle = error_of("G0 X0 Y0 Z5\nG81 X1 F100\n"), m98 = error_of("G0 X0\nM98\n");
  if (drom::machine::rs274_available()) {
    EXPECT_NE(cycle.find("prog.nc:2: LinuxCNC's interpreter"), std::string::npos) << cycle;  // G81 without its R plane
    EXPECT_NE(m98.find("prog.nc:2: LinuxCNC's interpreter"), std::string::npos) << m98;
  } else {
    EXPECT_NE(cycle.find("rs274 is not installed"), std::string::npos) << cycle;
  }
}

TEST(GCode, ArcsOutOfTheXyPlaneBecomeChordsAndCannedCyclesAreRead) {
  const auto path = parse_gcode("G21 G90\nG0 X0 Y0 Z0\nG18 G2 X10 Z0 I5 K0 F600\nM2\n", "xz.nc");
  ASSERT_GT(path.moves.size(), 20u);
  double longest = 0;
  for (std::size_t k = 1; k < path.moves.size(); ++k) {
    const Move& m = path.moves[k];
    EXPECT_EQ(m.kind, MoveKind::Linear);
    EXPECT_NEAR(std::hypot(m.end.x() - 5, m.end.z()), 5, 1e-9);  // every chord end on the circle
    // The chord's middle within 1 µm of the arc.
    EXPECT_LE(5 - std::hypot(0.5 * (m.start.x() + m.end.x()) - 5, 0.5 * (m.start.z() + m.end.z())), 1e-3 + 1e-12);
    EXPECT_NEAR(m.feed, 10, 1e-9);
    longest = std::max(longest, m.length());
  }
  EXPECT_LT(longest, 0.2);
  if (!drom::machine::rs274_available()) GTEST_SKIP() << "rs274 (linuxcnc-uspace) is not installed";
  const auto drilled = parse_gcode("G21 G90\nG0 X0 Y0 Z5\nG81 X10 Y10 Z-2 R1 F50\nG80\nM2\n", "drill.nc");
  ASSERT_EQ(drilled.moves.size(), 5u);  // the start, to the hole, down to R, drill, back up
  EXPECT_EQ(drilled.moves[3].kind, MoveKind::Linear);
  EXPECT_NEAR(drilled.moves[3].end.z(), -2, 1e-9);
  EXPECT_EQ(drilled.moves[3].source_line, 3);
}

// Issue 27: what the fuzzer found (fuzz/gcode.cpp, docs/robustness.md), each with the error expected.
TEST(GCode, HostileProgramsAreAClearErrorNotUndefinedBehaviourNorABoundlessPath) {
  // The first fuzz finding: an M word of 108 digits was cast to int (UBSan: float-cast-overflow).
  const std::string long_m = error_of("M" + std::string(107, '4') + "1M0\xe8S1M0M0S1");
  EXPECT_NE(long_m.find("prog.nc:1: word 'M4444"), std::string::npos) << long_m;
  EXPECT_NE(long_m.find("' is not a code drom knows"), std::string::npos) << long_m;
  // A byte that is not text is named by its code (and no interpreter is asked about it).
  EXPECT_NE(error_of(std::string("G0 X0\n\x01G1\n", 10)).find("prog.nc:2: expected a word letter, got '\\x01'"), std::string::npos);
  // 10^4 turns of an XZ circle of 0.9 km, in 1 um chords: 6.7e8 moves refused before one is made.
  const std::string helix = error_of("G0 X0 Y0 Z0\nG18 G2 X0 Z0 I900000 K0 P10000 F100\nM2\n");
  EXPECT_NE(helix.find("prog.nc:2: the program's moves (arcs split into turns and chords) pass 2000000"), std::string::npos) << helix;
}

TEST(GCode, WriteThenReadReproducesMoves) {
  Toolpath path;
  Move a;
  a.kind = MoveKind::Rapid;
  a.start = {0, 0, 5};
  a.end = {1, 2, 5};
  Move b;
  b.kind = MoveKind::Linear;
  b.start = a.end;
  b.end = {1, 2, -1};
  b.feed = 2;
  Move c;
  c.kind = MoveKind::ArcCCW;
  c.start = b.end;
  c.end = {11, 2, -1};
  c.centre = {6, 2, -1};
  c.feed = 10;
  c.tool_length_offset = 2;
  path.moves = {a, b, c};
  const auto back = parse_gcode(write_gcode(path, "test"), "roundtrip.nc");
  ASSERT_EQ(back.moves.size(), 4u);  // the first position is stated with a G0
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(back.moves[k + 1].kind, path.moves[k].kind);
    EXPECT_LT((back.moves[k + 1].end - path.moves[k].end).norm(), 1e-4);
    EXPECT_NEAR(back.moves[k + 1].feed, path.moves[k].feed, 1e-9);
    EXPECT_EQ(back.moves[k + 1].tool_length_offset, path.moves[k].tool_length_offset);
  }
  EXPECT_NEAR(back.moves[3].length(), M_PI * 5, 1e-6);
}

TEST(GCode, LinuxCncReadsWhatDromWritesToTheSameMoves) {
  if (!drom::machine::rs274_available()) GTEST_SKIP() << "rs274 (linuxcnc-uspace) is not installed";
  // A zigzag pocket with its arcs and tool-length offset, as levelset writes it.
  Toolpath path;
  Move m;
  m.kind = MoveKind::Rapid, m.start = {0, 0, 5}, m.end = {0, 0, 5};
  path.moves.push_back(m);
  m.kind = MoveKind::Linear, m.start = m.end, m.end = {0, 0, -2}, m.feed = 5, m.tool_length_offset = 1;
  path.moves.push_back(m);
  for (int pass = 0; pass < 6; ++pass) {
    Move line = m;
    line.kind = MoveKind::Linear;
    line.start = m.end;
    line.end = {pass % 2 ? 0.0 : 80.0, 10.0 * pass, -2};
    line.feed = 20;
    path.moves.push_back(line);
    Move turn = line;
    turn.kind = pass % 2 ? MoveKind::ArcCW : MoveKind::ArcCCW;
    turn.start = line.end;
    turn.end = {line.end.x(), line.end.y() + 10, -2};
    turn.centre = {line.end.x(), line.end.y() + 5, -2};
    path.moves.push_back(turn);
    m = turn;
  }
  const std::string text = write_gcode(path, "pocket");
  using drom::machine::ReaderChoice;
  expect_same_moves(drom::machine::parse_program(text, "pocket.nc", {ReaderChoice::Plain, {}}), drom::machine::parse_program(text, "pocket.nc", {ReaderChoice::Rs274, {}}));
}
