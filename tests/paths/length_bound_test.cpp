// The shortest cutting length under the seed's step-over model (paths/length_bound.hpp): a closed
// form on an inclined plane, never beaten by a path we plan, and the seed's chapter-3 Rubio lengths
// along the steepest slope, which lie below it (docs/finishing.md section 3).
#include "paths/clustering.hpp"
#include "paths/finishing_plan.hpp"
#include "paths/length_bound.hpp"
#include "paths/pca.hpp"
#include "paths/scallop_check.hpp"
#include "paths/surface_samples.hpp"
#include "tests/geometry/test_surfaces.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <stdexcept>

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

TEST(CuttingLengthBound, ConvergesOnTheTestSurfaces) {
  const Kinematics k;
  for (const bool rubio : {true, false}) {
    const auto s = rubio ? drom::tests::rubio_surface() : drom::tests::choi_surface();
    const double coarse = shortest_cutting_length(s, {}, kTorus, kScallop, k, 100).length, fine = shortest_cutting_length(s, {}, kTorus, kScallop, k, 400).length;
    EXPECT_NEAR(coarse, fine, 2e-4 * fine) << (rubio ? "Rubio" : "Choi");
    // Independent figures (a midpoint rule written in numpy, 300 x 300): area 3493.7 / 3240.8 mm²,
    // bound 4716 / 3669 mm.
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
    Zones whole;
    whole.zone.assign(6400, 0);
    whole.cluster = {0};
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
  Zones whole;
  whole.zone.assign(6400, 0);
  whole.cluster = {0};
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

TEST(CuttingLengthBound, TheSeedsRubioLengthsAlongTheSteepestSlopeLieBelowIt) {
  // Table 3.2, Rubio, each zone along its steepest slope with the torus: K-means (Euclid, PCA,
  // std-dev), RPCL (PCA) and Ward give 4634, 4626, 4612, 4593 and 4630 mm, links included. No
  // partition and no direction keeps eq. 2.3 at every point in passes shorter than the bound, so
  // the seed's paths there step wider than eq. 2.3 somewhere. Our model of its worst-point rule does
  // not (every torus path above is longer than the bound), so these rows depend on a detail of its
  // planner the text does not give (docs/finishing.md section 3).
  const double bound = shortest_cutting_length(drom::tests::rubio_surface(), {}, kTorus, kScallop, Kinematics{}).length;
  for (const double seed : {4634.0, 4626.0, 4612.0, 4593.0, 4630.0}) EXPECT_LT(seed, bound);
  // And by how much: 1.7-2.6 % below.
  EXPECT_GT(bound, 1.015 * 4634);
}

TEST(CuttingLengthBound, RefusesBadSettings) {
  const auto s = drom::tests::rubio_surface();
  EXPECT_THROW(shortest_cutting_length(s, {}, kTorus, 0, Kinematics{}), std::invalid_argument);
  EXPECT_THROW(shortest_cutting_length(s, {}, kTorus, 2.5, Kinematics{}), std::invalid_argument);
  EXPECT_THROW(shortest_cutting_length(s, {}, kTorus, kScallop, Kinematics{}, 0), std::invalid_argument);
}

}  // namespace
