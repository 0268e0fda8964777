// The shortest cutting length of a path that keeps eq. 2.3 at every point (paths/finish/length_bound.hpp):
// a closed form on planes, trimmed faces, never beaten by the flat model's paths; what goes below it
// (the seed's worst-point rule and edge convention), and the seed's chapter-3 Rubio lengths along the
// steepest slope, which lie below it (docs/finishing.md sections 3 and 5).
#include "paths/finish/clustering.hpp"
#include "paths/cutter/stepover.hpp"
#include "paths/finish/finishing_plan.hpp"
#include "paths/finish/length_bound.hpp"
#include "paths/finish/pca.hpp"
#include "paths/finish/scallop_check.hpp"
#include "paths/finish/surface_samples.hpp"
#include "tests/geometry/test_surfaces.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace {

using namespace drom::paths;
constexpr double kDeg = std::numbers::pi / 180;
const Tool kTorus{ToolKind::torus, 5, 2}, kBall{ToolKind::ball, 5, 5};
constexpr double kScallop = 0.01;

drom::geometry::NurbsSurface plane_at(double slope, double width, double height) {
  const double c = std::cos(slope), s = std::sin(slope);
  return drom::geometry::NurbsSurface::bezier(2, 2, {{0, 0, 0}, {0, width, 0}, {height * c, 0, height * s}, {height * c, width, height * s}});
}

FinishingSettings settings(const Tool& tool, StepoverModel model) {
  FinishingSettings fs;
  fs.tool = tool;
  fs.stepover = model;
  fs.accounting = Accounting::seed;
  return fs;
}

// One zone over the 80 x 80 samples.
Zones whole_surface() {
  Zones z;
  z.zone.assign(6400, 0);
  z.cluster = {0};
  return z;
}

FinishingPlan plan(const drom::geometry::NurbsSurface& surface, const Zones& zones, const std::vector<ZoneSetup>& setups, const Tool& tool,
                   StepoverModel model) {
  return plan_finishing(build_machining_mesh(surface, {}, 0.5, 80, 80), zones, setups, settings(tool, model));
}

TEST(CuttingLengthBound, IsAreaOverTheStepOnAnInclinedPlane) {
  // Constant slope: the integrand is constant, so the bound is the area over eq. 2.3's step at
  // eq. 1.5's radius along the slope, (R - r) / sin(s) + r (ball: R), whatever the grid.
  const Kinematics k;
  for (const double slope_deg : {20.0, 60.0}) {
    const auto plane = plane_at(slope_deg * kDeg, 56, 28);
    const double radius = 3 / std::sin(slope_deg * kDeg) + 2;
    const double step = 2 * std::sqrt(2 * kScallop * radius - kScallop * kScallop);
    for (const int cells : {1, 7, 50}) {
      const CuttingLengthBound b = shortest_cutting_length(plane, {}, kTorus, kScallop, k, cells);
      EXPECT_NEAR(b.area, 56.0 * 28.0, 1e-9);
      EXPECT_NEAR(b.length, 56.0 * 28.0 / step, 1e-9) << slope_deg << " deg, " << cells << " cells";
      EXPECT_NEAR(b.time, b.length / k.feed, 1e-12);
    }
    const CuttingLengthBound ball = shortest_cutting_length(plane, {}, kBall, kScallop, k, 5);
    EXPECT_NEAR(ball.length, 56.0 * 28.0 / (2 * std::sqrt(2 * kScallop * 5 - kScallop * kScallop)), 1e-9);
  }
  // Level ground: the torus's flat bottom caps eq. 1.5's infinite radius.
  const CuttingLengthBound level = shortest_cutting_length(plane_at(0, 56, 28), {}, kTorus, kScallop, k, 4);
  EXPECT_NEAR(level.length, 56.0 * 28.0 / level_ground_stepover(kTorus, kScallop), 1e-9);
}

TEST(CuttingLengthBound, CountsOnlyWhatLiesInsideTheTrimLoops) {
  // A triangle, half the plane's parameter square: half the area, half the length, to the cells
  // the diagonal crosses (O(1 / cells)).
  const auto plane = plane_at(60 * kDeg, 56, 28);
  const drom::geometry::TrimLoops half({{{0, 0}, {1, 0}, {0, 1}}});
  const CuttingLengthBound whole = shortest_cutting_length(plane, {}, kTorus, kScallop, Kinematics{}, 200);
  const CuttingLengthBound b = shortest_cutting_length(plane, half, kTorus, kScallop, Kinematics{}, 200);
  EXPECT_NEAR(b.area, 0.5 * whole.area, 0.01 * whole.area);
  EXPECT_NEAR(b.length, 0.5 * whole.length, 0.01 * whole.length);
  EXPECT_NEAR(b.length / b.area, whole.length / whole.area, 1e-12);  // the same step everywhere
}

TEST(CuttingLengthBound, ConvergesOnTheTestSurfaces) {
  const Kinematics k;
  for (const bool rubio : {true, false}) {
    const auto s = rubio ? drom::tests::rubio_surface() : drom::tests::choi_surface();
    const double coarse = shortest_cutting_length(s, {}, kTorus, kScallop, k, 100).length, fine = shortest_cutting_length(s, {}, kTorus, kScallop, k, 400).length;
    EXPECT_NEAR(coarse, fine, 2e-4 * fine) << (rubio ? "Rubio" : "Choi");
    // Pinned to a separate midpoint rule (numpy, 300 x 300, evaluating the Bézier patches from
    // their control points): area 3493.7 / 3240.8 mm², bound 4716 / 3669 mm.
    const CuttingLengthBound b = shortest_cutting_length(s, {}, kTorus, kScallop, k, 300);
    EXPECT_NEAR(b.area, rubio ? 3493.7 : 3240.8, 0.1);
    EXPECT_NEAR(b.length, rubio ? 4716 : 3669, 1.0);
  }
}

TEST(CuttingLengthBound, NoPathThatKeepsEquation23AtEveryPointIsShorter) {
  // The flat model (eq. 2.3 at every contact point, the plane step the least over the pass), whole
  // surface and the K = 3 partitions of the seed's protocol, torus and ball, in several directions:
  // the passes alone are never shorter than the bound.
  const Kinematics k;
  for (const bool rubio : {true, false}) {
    const auto s = rubio ? drom::tests::rubio_surface() : drom::tests::choi_surface();
    const SurfaceSamples samples = sample_surface(s, {}, 80, 80);
    const Zones whole = whole_surface();
    const Zones three = connected_zones(kmeans(samples, s, 3, {}), 80, 80);
    const auto shapes = describe_zones(samples, three);
    for (const Tool& tool : {kTorus, kBall}) {
      const double bound = shortest_cutting_length(s, {}, tool, kScallop, k).length;
      for (const double azimuth : {-60.0, 0.0, 30.0, 67.0, 90.0}) {
        const FinishingPlan p = plan(s, whole, {ZoneSetup{azimuth * kDeg}}, tool, StepoverModel::flat);
        EXPECT_GT(p.pass_length(), bound) << (rubio ? "Rubio " : "Choi ") << tool.name() << " at " << azimuth << " deg";
      }
      std::vector<ZoneSetup> steepest;
      for (const auto& z : shapes) steepest.push_back(ZoneSetup{z.steepest_azimuth});
      EXPECT_GT(plan(s, three, steepest, tool, StepoverModel::flat).pass_length(), bound) << (rubio ? "Rubio " : "Choi ") << tool.name() << ", K = 3";
      // The seed's worst-point rule with the torus along each zone's steepest slope, as in its
      // chapter 3, stays above it too.
      if (tool.kind == ToolKind::torus) {
        EXPECT_GT(plan(s, three, steepest, tool, StepoverModel::seed).pass_length(), bound) << (rubio ? "Rubio" : "Choi") << ", seed's rule, K = 3";
      }
    }
  }
}

TEST(CuttingLengthBound, TheSeedsWorstPointRuleCanGoBelowIt) {
  // The seed places the next plane from the point of least effective radius alone. A ball's radius
  // is the same everywhere, so the first point of the pass sets the plane step, and where the
  // surface tilts across the pass more than there, the step along the surface exceeds eq. 2.3: on
  // Rubio fed at -60 deg the seed's rule finishes in 12 % less than the bound and leaves 1.5 sh
  // (the scallop simulated, inside the surface); eq. 2.3 at every point keeps sh.
  const auto s = drom::tests::rubio_surface();
  const Zones whole = whole_surface();
  const double bound = shortest_cutting_length(s, {}, kBall, kScallop, Kinematics{}).length;
  const FinishingPlan seed = plan(s, whole, {ZoneSetup{-60 * kDeg}}, kBall, StepoverModel::seed);
  EXPECT_LT(seed.pass_length(), 0.9 * bound);
  const FinishingPlan flat = plan(s, whole, {ZoneSetup{-60 * kDeg}}, kBall, StepoverModel::flat);
  const ScallopCheck wide = check_scallop(s, seed.zones, kBall, 0.2, 0.8, 0.2, 0.8, 30, 30), kept = check_scallop(s, flat.zones, kBall, 0.2, 0.8, 0.2, 0.8, 30, 30);
  // Measured: the seed's rule 4874 mm and 0.0153 mm of scallop; eq. 2.3 at every point 6200 mm and 0.0087 mm.
  EXPECT_GT(wide.max_height, 1.4 * kScallop);
  EXPECT_LE(kept.max_height, kScallop);
  EXPECT_GT(flat.pass_length(), bound);
}

TEST(CuttingLengthBound, TheSeedsEdgeConventionCanGoBelowItOnAPlane) {
  // On Table 2.1's plane, where eq. 2.3 is exact and every point ties, the seed's model stops
  // planning once the next plane would pass the far edge and leaves the band beyond the last pass to
  // its half step: 44 passes of 56 mm, 0.7 % below the floor. The flat model reaches the edge.
  const auto plane = plane_at(60 * kDeg, 56, 28);
  const Zones whole = whole_surface();
  const double bound = shortest_cutting_length(plane, {}, kBall, kScallop, Kinematics{}).length;
  const double seed = plan(plane, whole, {ZoneSetup{90 * kDeg}}, kBall, StepoverModel::seed).pass_length();
  EXPECT_LT(seed, bound);
  EXPECT_GT(seed, 0.99 * bound);
  EXPECT_GT(plan(plane, whole, {ZoneSetup{90 * kDeg}}, kBall, StepoverModel::flat).pass_length(), bound);
}

TEST(CuttingLengthBound, TheSeedsRubioLengthsAlongTheSteepestSlopeLieBelowIt) {
  // Table 3.2, Rubio, each zone along its steepest slope with the torus: K-means (Euclid, PCA,
  // std-dev), RPCL (PCA) and Ward give 4634, 4626, 4612, 4593 and 4630 mm, links included: 1.7-2.6 %
  // below the floor. A path gets there only by stepping wider than eq. 2.3 somewhere or leaving part
  // of the edges uncut, and the seed's edge convention is worth 0.7 % on the plane above. Our model
  // of the seed's planner, with its edge convention, keeps its passes alone 6.4 % or more above the
  // floor over 546 K = 3 partitions (bench/zoning_scan weights rubio); 8.8 % on this one.
  const auto s = drom::tests::rubio_surface();
  const double bound = shortest_cutting_length(s, {}, kTorus, kScallop, Kinematics{}).length;
  for (const double seed : {4634.0, 4626.0, 4612.0, 4593.0, 4630.0}) EXPECT_LT(seed, bound);
  const SurfaceSamples samples = sample_surface(s, {}, 80, 80);
  const Zones three = connected_zones(kmeans(samples, s, 3, {}), 80, 80);
  std::vector<ZoneSetup> steepest;
  for (const auto& z : describe_zones(samples, three)) steepest.push_back(ZoneSetup{z.steepest_azimuth});
  EXPECT_GT(plan(s, three, steepest, kTorus, StepoverModel::seed).pass_length(), 1.06 * bound);
}

TEST(CuttingLengthBound, RefusesBadSettingsSayingWhatItExpected) {
  const auto s = drom::tests::rubio_surface();
  const auto message = [&](double scallop, Kinematics k, int cells, const Eigen::Vector3d& axis) {
    try {
      shortest_cutting_length(s, {}, kTorus, scallop, k, cells, axis);
    } catch (const std::invalid_argument& e) {
      return std::string(e.what());
    }
    return std::string("accepted");
  };
  const Eigen::Vector3d z = Eigen::Vector3d::UnitZ();
  EXPECT_EQ(message(0, {}, 10, z), "shortest_cutting_length: the scallop height must lie in (0, r = 2] mm, got 0");
  EXPECT_EQ(message(2.5, {}, 10, z), "shortest_cutting_length: the scallop height must lie in (0, r = 2] mm, got 2.5");
  EXPECT_EQ(message(1e-7, {}, 10, z), "accepted");
  EXPECT_NE(message(std::nan(""), {}, 10, z).find("got nan"), std::string::npos);
  EXPECT_EQ(message(kScallop, {}, 0, z), "shortest_cutting_length: cells must be at least 1, got 0");
  EXPECT_EQ(message(kScallop, Kinematics{0, 6000, 40000}, 10, z), "shortest_cutting_length: the feed must be a positive number of mm/s, got 0");
  EXPECT_EQ(message(kScallop, {}, 10, Eigen::Vector3d::Zero()), "shortest_cutting_length: the tool axis must be a finite nonzero vector, got (0, 0, 0)");
  EXPECT_NE(message(kScallop, {}, 10, Eigen::Vector3d(0, std::nan(""), 1)).find("tool axis"), std::string::npos);
}

}  // namespace
