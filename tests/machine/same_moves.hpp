#pragma once
// Two readings of one program hold the same moves, to the interpreter's printed precision
// (4 decimals of the program unit; `unit` is the largest program unit used, in mm).
#include "machine/nc_program.hpp"

#include <gtest/gtest.h>

inline void expect_same_moves(const drom::machine::NcProgram& a, const drom::machine::NcProgram& b, double unit = 1.0) {
  using drom::machine::MoveType;
  ASSERT_EQ(a.moves.size(), b.moves.size()) << a.origin;
  const double tol = 1e-4 * unit;
  for (std::size_t i = 0; i < a.moves.size(); ++i) {
    const drom::machine::NcMove &x = a.moves[i], &y = b.moves[i];
    EXPECT_EQ(static_cast<int>(x.type), static_cast<int>(y.type)) << "move " << i << " line " << x.line;
    EXPECT_EQ(x.line, y.line) << "move " << i;
    for (int k = 0; k < 6; ++k) EXPECT_NEAR(x.end[k], y.end[k], tol) << "move " << i << " axis " << k << " line " << x.line;
    if (x.type == MoveType::Arc) {
      EXPECT_EQ(x.plane, y.plane) << "move " << i;
      EXPECT_EQ(x.rotation, y.rotation) << "move " << i;
      EXPECT_LE((x.centre - y.centre).norm(), 2 * tol) << "move " << i;
    }
    if (x.type == MoveType::Linear || x.type == MoveType::Arc) {
      // A feed per length: the length read back carries the coordinates' rounding too.
      const double length = x.reference_length(), rounding = x.feed_mode == drom::machine::FeedMode::UnitsPerMinute && length > 0 ? 2 * tol / length : 0.0;
      EXPECT_NEAR(x.programmed_duration(), y.programmed_duration(), (1e-4 + rounding) * x.programmed_duration() + 1e-9) << "move " << i << " line " << x.line;
    }
    if (x.type == MoveType::Dwell) {
      EXPECT_NEAR(x.dwell, y.dwell, 1e-4);
    }
    EXPECT_EQ(x.stop_before, y.stop_before) << "move " << i << " line " << x.line;
    EXPECT_EQ(x.tool_length_offset, y.tool_length_offset) << "move " << i << " line " << x.line;
  }
}
