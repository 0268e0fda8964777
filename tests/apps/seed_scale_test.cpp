// drom run on the curved panel at the seed's full scale (`--set run.scale=seed`: the case files
// as written), against the figures stored from this machine's runs and the targets where we
// meet them. Not in the default suite (label `slow`): on this 2-core machine the curved panel takes
// about 11 min. The flat plate's run (at most 70 min here) is measured in docs/closed-loop.md §4, not
// repeated in a test. Run it with
//   ctest --test-dir build -L slow -R SeedScale --output-on-failure
// docs/closed-loop.md §4 gives the same figures beside the seed's.
#include "run_checks.hpp"

#include <gtest/gtest.h>

#include <string>

TEST(SeedScale, CurvedPanelMeetsItsTargets) {
  const auto s = check_run("seed_panel", std::string(" ") + DROM_SOURCE_DIR + "/cases/curved_panel.toml --set run.scale=seed",
                           {0.037402, 2.658e-4, 1.449e-3, 1, 5.902e-3});
  ASSERT_FALSE(s.is_null());
  EXPECT_EQ(s["scale"], "seed");
  EXPECT_TRUE(s["targets"]["path_error_from_pass3_met"].get<bool>());
  EXPECT_TRUE(s["targets"]["final_shape_by_target_pass_met"].get<bool>());
}
