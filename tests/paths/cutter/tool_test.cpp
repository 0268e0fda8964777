// The one cutter model against closed forms: the lower profile, the signed distance on and off the
// cutter's surface, the contact-to-tip offset, and the assembly's profile with shank and holder.
#include "paths/cutter/stepover.hpp"
#include "paths/cutter/tool_assembly.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

using namespace drom::paths;

namespace {

// The three end mills of a shop's rack, all with 20 mm of flutes.
const ToolAssembly kBall = ToolAssembly::ball(5, 20), kBull = ToolAssembly::bull_nose(5, 2, 20), kFlat = ToolAssembly::flat(5, 20);

// The lower profile written from the torus's definition (a disc of radius R - r at height r grown by
// r), independently of bottom_height's branches.
double torus_bottom(double R, double r, double rho) {
  if (rho <= R - r) return 0;
  const double d = rho - (R - r);
  return r - std::sqrt(r * r - d * d);
}

}  // namespace

TEST(Cutter, LowerProfileIsTheTorusOfEveryEndMill) {
  for (double rho = 0; rho <= 5; rho += 0.125) {
    EXPECT_NEAR(kBall.bottom_height(rho), 5 - std::sqrt(25 - rho * rho), 1e-12) << rho;
    EXPECT_NEAR(kBull.bottom_height(rho), torus_bottom(5, 2, rho), 1e-12) << rho;
    EXPECT_EQ(kFlat.bottom_height(rho), 0) << rho;
    EXPECT_EQ(kBull.bottom_height(-rho), kBull.bottom_height(rho));
  }
  EXPECT_NEAR(kBull.bottom_height(5), 2, 1e-12);
  EXPECT_NEAR(kBall.bottom_height(7), 5, 1e-12);  // beyond R: the corner's top
}

TEST(Cutter, SignedDistanceVanishesOnTheSurfaceAndHasTheRightSign) {
  for (const ToolAssembly* tool : {&kBall, &kBull, &kFlat}) {
    for (double rho = 0.05; rho < 4.95; rho += 0.1) {
      const double h = tool->bottom_height(rho);
      EXPECT_NEAR(tool->signed_distance(rho, h), 0, 1e-9) << tool->cutter.name() << " rho " << rho;
      EXPECT_LT(tool->signed_distance(rho, h + 0.01), 0);
      EXPECT_GT(tool->signed_distance(rho, h - 0.01), 0);
    }
    // The side: a cylinder of radius R up to the flutes, cut flat there.
    EXPECT_NEAR(tool->signed_distance(5.5, 10), 0.5, 1e-12);
    EXPECT_NEAR(tool->signed_distance(2, 20.25), 0.25, 1e-12);
    EXPECT_NEAR(tool->signed_distance(0, -1), 1, 1e-12);
    EXPECT_EQ(tool->section_radius(21), 0);
    EXPECT_NEAR(tool->section_radius(10), 5, 1e-12);
  }
}

TEST(Cutter, TheContactPointLiesOnTheCutterAtTheNormal) {
  const Eigen::Vector3d axis = Eigen::Vector3d(0.3, -0.2, 1).normalized();
  for (const ToolAssembly* tool : {&kBall, &kBull}) {
    for (const Eigen::Vector3d& n0 : {Eigen::Vector3d(0.5, 0.1, 1), Eigen::Vector3d(-0.2, 0.7, 1), Eigen::Vector3d(0.3, -0.2, 1)}) {
      const Eigen::Vector3d n = n0.normalized(), cc(10, -4, 3);
      const Eigen::Vector3d tip = cutter_location(cc, n, tool->cutter, axis);
      EXPECT_NEAR(signed_distance(*tool, {tip, axis}, cc), 0, 1e-9) << tool->cutter.name();
      // The surface's normal there is n: a step along -n leaves the cutter, one along +n enters it.
      EXPECT_NEAR(signed_distance(*tool, {tip, axis}, cc - 0.01 * n), 0.01, 1e-6);
      EXPECT_NEAR(signed_distance(*tool, {tip, axis}, cc + 0.01 * n), -0.01, 1e-6);
    }
  }
}

TEST(Cutter, AssemblyProfileStepsUpAtTheShankAndTheHolder) {
  ToolAssembly tool{Tool::ball(3), 12, 4, 40, RevolvedProfile::endless_cylinder(26.5)};
  EXPECT_NEAR(profile_height(tool, 2), 3 - std::sqrt(9 - 4.0), 1e-12);
  EXPECT_EQ(profile_height(tool, 3.5), 12);  // the shank, wider than the cutter
  EXPECT_EQ(profile_height(tool, 20), 40);   // the holder's face
  EXPECT_EQ(profile_height(tool, 27), std::numeric_limits<double>::infinity());
  EXPECT_EQ(tool.reach(), 26.5);
  EXPECT_EQ(tool.name(), "ball R3, shank D8, holder D53 at 40 mm");
  tool.holder = {};
  EXPECT_FALSE(tool.has_holder());
  EXPECT_EQ(profile_height(tool, 20), std::numeric_limits<double>::infinity());
}

TEST(Cutter, ShortDescriptionsAreParsedOrRefusedByName) {
  const Tool b = parse_tool("ball:6", "--tool"), t = parse_tool("torus:10:2", "--tool"), f = parse_tool("flat:8", "--tool");
  EXPECT_EQ(b.kind, ToolKind::ball);
  EXPECT_EQ(b.corner_radius, 3);
  EXPECT_EQ(t.radius, 5);
  EXPECT_EQ(t.corner_radius, 2);
  EXPECT_TRUE(is_flat(f));
  EXPECT_EQ(f.name(), "flat R4");
  EXPECT_THROW(parse_tool("torus:10:6", "--tool"), std::exception);
  EXPECT_THROW(parse_tool("cone:10", "--tool"), std::exception);
  EXPECT_THROW(ToolAssembly::bull_nose(5, 5, 20), std::invalid_argument);
}

// The step-over on level ground: eq. 2.3 for a ball, flat bottom plus two corner traces for a torus;
// the torus's flat bottom leaves nothing, as the levelset's pocket model has it.
TEST(Cutter, LevelGroundStepoverLeavesTheScallopItIsAskedFor) {
  EXPECT_NEAR(flat_scallop(level_ground_stepover(kBall.cutter, 0.01), 5), 0.01, 1e-12);
  const double w = level_ground_stepover(kBull.cutter, 0.01);
  EXPECT_NEAR(flat_scallop(w - 2 * 3, 2), 0.01, 1e-12);
}
