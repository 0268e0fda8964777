// Issue 24's checks 3 (the bump's tilt against the obstacle mesh and the aggregation) and 6 (the
// corner: the longer tool tilts less, and the axis returns without overshoot).
#include "paths/orient/orient_scene.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace drom::paths {
namespace {

constexpr double kDeg = 180 / std::numbers::pi;

double max_tilt_deg(const AxisHistory& h) {
  double worst = 0;
  for (const auto& a : h.samples) worst = std::max(worst, std::acos(std::clamp(a.axis.dot(a.programmed_axis), -1.0, 1.0)));
  return worst * kDeg;
}

// §3-3.2: the tool reduced to G, the seed's parameters (Table 3.1), the bump meshed at 3 and 1 mm.
AxisHistory bump_run(double spacing, Aggregation aggregation) {
  const OrientScene scene = bump_scene({});
  const KhatibParameters k;  // eta = 1e-7 N m^3, r0 = 10 mm
  const ObstacleCloud obstacles = scene_obstacles(scene, spacing, k.influence_radius);
  const DirectField field(obstacles, k, aggregation);
  DynamicsSettings st;
  st.moment = MomentModel::PointG;
  st.lever_g = 20;
  return integrate_axis(scene.passes.front(), {}, field, st);
}

TEST(OrientBump, TiltGrowsWithMeshDensityUnderF1) {
  const double coarse = max_tilt_deg(bump_run(3, Aggregation::F1)), fine = max_tilt_deg(bump_run(1, Aggregation::F1));
  std::cout << "F1: " << coarse << " deg (3 mm), " << fine << " deg (1 mm)\n";
  EXPECT_NEAR(coarse, 8, 2) << "seed: about 8 deg with a 3 mm mesh";
  EXPECT_NEAR(fine, 15, 4) << "seed: about 15 deg with a 1 mm mesh";
}

TEST(OrientBump, F2AndF3DoNotDependOnMeshDensity) {
  for (Aggregation a : {Aggregation::F2, Aggregation::F3}) {
    const double coarse = max_tilt_deg(bump_run(3, a)), fine = max_tilt_deg(bump_run(1, a));
    std::cout << aggregation_name(a) << ": " << coarse << " deg (3 mm), " << fine << " deg (1 mm)\n";
    EXPECT_GT(coarse, 0.5) << aggregation_name(a);
    EXPECT_NEAR(fine / coarse, 1, 0.25) << aggregation_name(a) << ": " << coarse << " deg (3 mm) vs " << fine << " deg (1 mm)";
    EXPECT_LT(fine, 4 * 15) << aggregation_name(a) << ": the same order as F1";
  }
}

struct CornerRun {
  double max_deviation_deg = 0, overshoot_deg = 0;
};

CornerRun corner_run(double stick_out) {
  CornerOptions o;
  o.stick_out = stick_out;
  o.roll = -0.3;
  const OrientScene scene = corner_scene(o);
  const KhatibParameters k;
  const ObstacleCloud obstacles = scene_obstacles(scene, 2, k.influence_radius);
  const DirectField field(obstacles, k, Aggregation::F1);
  const auto nodes = tool_skin_nodes(scene.tool, 0, 1.5);
  DynamicsSettings st;
  st.moment = MomentModel::Direction;
  const AxisHistory h = integrate_axis(scene.passes.front(), nodes, field, st);
  CornerRun r;
  std::size_t peak = 0;
  for (std::size_t i = 0; i < h.samples.size(); ++i) {
    const double d = std::acos(std::clamp(h.samples[i].axis.dot(h.samples[i].programmed_axis), -1.0, 1.0)) * kDeg;
    if (d > r.max_deviation_deg) {
      r.max_deviation_deg = d;
      peak = i;
    }
  }
  // After the last obstacle the roll relaxes to -0.3 rad: it must not cross it (critical damping).
  const double sign = h.samples[peak].roll > -0.3 ? 1 : -1;
  for (std::size_t i = peak; i < h.samples.size(); ++i) r.overshoot_deg = std::max(r.overshoot_deg, -sign * (h.samples[i].roll + 0.3) * kDeg);
  EXPECT_NEAR(h.samples.back().roll, -0.3, 0.01) << "the axis returns to its programmed roll";
  return r;
}

TEST(OrientCorner, LongerToolTiltsLessAndReturnsWithoutOvershoot) {
  const CornerRun short_tool = corner_run(20), long_tool = corner_run(30);
  std::cout << "corner: 20 mm tool " << short_tool.max_deviation_deg << " deg (overshoot " << short_tool.overshoot_deg << "), 30 mm tool "
            << long_tool.max_deviation_deg << " deg (overshoot " << long_tool.overshoot_deg << ")\n";
  EXPECT_GT(short_tool.max_deviation_deg, 2.0);
  EXPECT_LT(long_tool.max_deviation_deg, 0.8 * short_tool.max_deviation_deg)
      << "20 mm: " << short_tool.max_deviation_deg << " deg, 30 mm: " << long_tool.max_deviation_deg << " deg";
  EXPECT_LT(short_tool.overshoot_deg, 0.01 * short_tool.max_deviation_deg + 1e-3);
  EXPECT_LT(long_tool.overshoot_deg, 0.01 * long_tool.max_deviation_deg + 1e-3);
}

}  // namespace
}  // namespace drom::paths
