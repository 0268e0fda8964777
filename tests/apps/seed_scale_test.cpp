// drom run on both cases at the seed's full scale (`--set run.scale=seed`: the case files as
// written), against the figures stored from this machine's runs and the targets where we
// meet them. Not in the default suite (label `slow`): on this 2-core machine the curved panel's run
// took 3 min 0 s and the flat plate's 3 min 16 s (2026-11-28, docs/benchmarks.md). Run them with
//   ctest --test-dir build -L slow -R SeedScale --output-on-failure
// docs/closed-loop.md §4 gives the same figures beside the seed's.
#include "run_checks.hpp"

#include <gtest/gtest.h>

#include <string>

TEST(SeedScale, CurvedPanelMeetsItsTargets) {
  const auto s = check_run("seed_panel", std::string(" ") + DROM_SOURCE_DIR + "/cases/curved_panel.toml --set run.scale=seed",
                           {0.037911, 2.682e-4, 1.364e-3, 1, 7.203e-3});  // before issue 29: {0.037402, 2.658e-4, 1.449e-3, 1, 5.902e-3}
  ASSERT_FALSE(s.is_null());
  EXPECT_EQ(s["scale"], "seed");
  EXPECT_TRUE(s["targets"]["path_error_from_pass3_met"].get<bool>());
  EXPECT_TRUE(s["targets"]["final_shape_by_target_pass_met"].get<bool>());
}

// The flat plate meets its path target; its final shape at the end of pass 3 (0.049 mm on this draw,
// inside the 95 % band) is over the 0.02 mm target, so it is held to its stored figure instead: the
// posterior sd there is 0.033 mm (docs/closed-loop.md §4).
TEST(SeedScale, FlatPlateMatchesItsStoredFigures) {
  const auto s = check_run("seed_flat", " --set run.scale=seed", {1.6390, 3.920e-4, 2.229e-4, 1, 0.048913});
  ASSERT_FALSE(s.is_null());
  EXPECT_EQ(s["scale"], "seed");
  EXPECT_TRUE(s["targets"]["path_error_from_pass3_met"].get<bool>());
  EXPECT_GE(s["headline"]["final_shape_band95_coverage_end"].get<double>(), 0.95);
}
