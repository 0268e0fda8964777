// The tool axis relaxed under the machine's limits: the guide surface kept, the effective radius of
// the seed's formulas, and on the saddle near the table-table singularity a pass faster than at 1°
// and than the seed's manual heuristic (5° imposed over the C-saturated zone).
#include "machine/cl_data.hpp"
#include "paths/cutter/stepover.hpp"
#include "paths/orient/orientation_under_limits.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

using namespace drom;
using namespace drom::paths;

namespace {

constexpr double kDeg = std::numbers::pi / 180;

// A pass along x over z = (x² - y²) / (2c) at y = y0.
SurfacePass saddle_pass(double c, double y0, double step, double feed) {
  SurfacePass pass;
  pass.feed = feed;
  for (double x = -30; x <= 30 + 1e-9; x += step) {
    PassPoint p;
    p.contact = {x, y0, (x * x - y0 * y0) / (2 * c)};
    p.normal = Eigen::Vector3d(-x / c, y0 / c, 1).normalized();
    p.feed = Eigen::Vector3d(1, 0, x / c).normalized();
    // Across the feed (along y), z = -y²/2c bends away from the tool: convex, curvature -1/c.
    p.cross_curvature = -1 / c;
    pass.points.push_back(p);
  }
  return pass;
}

}  // namespace

TEST(OrientationUnderLimits, ThePoseKeepsTheContactPointAndItsNormal) {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(-1, 1);
  const Tool tool = Tool::torus(5, 1.5);
  for (int trial = 0; trial < 1000; ++trial) {
    PassPoint p;
    p.contact = {10 * u(rng), 10 * u(rng), 3 * u(rng)};
    p.normal = Eigen::Vector3d(0.3 * u(rng), 0.3 * u(rng), 1).normalized();
    p.feed = p.normal.cross(Eigen::Vector3d(u(rng), u(rng), u(rng))).normalized();
    const Orientation o{std::abs(u(rng)) * 30 * kDeg + 0.5 * kDeg, u(rng) * std::numbers::pi};
    const machine::ClPose pose = tool_pose(p, tool, o);
    // The torus: its corner circle (radius R - r) centred on the axis r above the tip.
    const Eigen::Vector3d centre = pose.tip + tool.corner_radius * pose.axis;
    Eigen::Vector3d radial = p.contact - centre;
    radial -= pose.axis * pose.axis.dot(radial);
    const Eigen::Vector3d tube = centre + (tool.radius - tool.corner_radius) * radial.normalized();
    EXPECT_NEAR((p.contact - tube).norm(), tool.corner_radius, 1e-12);
    EXPECT_LE(((tube - p.contact) / tool.corner_radius - p.normal).norm(), 1e-12);  // touching, with S's normal
    EXPECT_LE((tube - (p.contact + tool.corner_radius * p.normal)).norm(), 1e-12);  // on the guide surface S1
    EXPECT_NEAR(std::acos(pose.axis.dot(p.normal)), o.tilt, 1e-12);
  }
}

TEST(OrientationUnderLimits, EffectiveRadiusAndScallopMatchTheSeeds) {
  // 003-digest §2.4 (R 5, r 1.5, lead tilt, D = 8 mm): R_eff 202.0 / 41.7 mm, scallop 0.040 / 0.192 mm at 1° / 5°.
  const Tool tool = Tool::torus(5, 1.5);
  EXPECT_NEAR(effective_radius(tool, {1 * kDeg, 0}), 202.0, 0.05);
  EXPECT_NEAR(effective_radius(tool, {5 * kDeg, 0}), 41.7, 0.05);
  EXPECT_NEAR(flat_scallop(8, effective_radius(tool, {1 * kDeg, 0})), 0.040, 0.0005);
  EXPECT_NEAR(flat_scallop(8, effective_radius(tool, {5 * kDeg, 0})), 0.192, 0.0005);
  EXPECT_NEAR(effective_radius(tool, {5 * kDeg, std::numbers::pi / 2}), tool.corner_radius, 1e-12);  // tilted across the feed: the corner
  EXPECT_NEAR(effective_radius(Tool::ball(5), {20 * kDeg, 0.3}), 5, 1e-12);                          // a ball
}

TEST(OrientationUnderLimits, ASaddlePassNearTheSingularityIsRelaxedFasterThanTheSeedsHeuristic) {
  const machine::Machine m = machine::load_machine("ucp710_like", {"control.junction=smooth", "control.junction_tolerance_rotary=0.05"});
  const machine::Kinematics kin(m);
  const Tool tool = Tool::torus(5, 1.5);
  const SurfacePass pass = saddle_pass(100, 0, 0.25, 3000);
  const std::size_t n = pass.points.size();
  // Programmed: 1° across the feed, the pass crossing the singularity's neighbourhood at x = 0.
  const std::vector<Orientation> programmed(n, {1 * kDeg, std::numbers::pi / 2});
  RelaxationSettings settings;
  settings.stepover = 4;
  const PassOrientation relaxed = relax_orientation(pass, tool, programmed, kin, settings);
  // The seed's heuristic, at its best: a tilt imposed where the 1° pass runs slowest (x = 0), blended
  // into the programmed 1° over a radius; the tilt (2° to 5°) and the radius (5 to 20 mm) scanned.
  double heuristic_time = 1e300, best_top = 0, best_radius = 0;
  for (double top : {2.0, 3.0, 4.0, 5.0})
    for (double radius : {5.0, 10.0, 15.0, 20.0}) {
      std::vector<Orientation> heuristic = programmed;
      for (std::size_t i = 0; i < n; ++i) {
        const double x = pass.points[i].contact.x(), w = std::abs(x) < radius ? 0.5 * (1 + std::cos(std::numbers::pi * x / radius)) : 0.0;
        heuristic[i].tilt = (1 + (top - 1) * w) * kDeg;
      }
      const double t = pass_time(pass, tool, heuristic, kin);
      if (t < heuristic_time) heuristic_time = t, best_top = top, best_radius = radius;
    }
  RecordProperty("heuristic_best_tilt_deg", std::to_string(best_top));
  RecordProperty("heuristic_best_radius_mm", std::to_string(best_radius));
  RecordProperty("time_1deg_s", std::to_string(relaxed.time_before));
  RecordProperty("time_heuristic_s", std::to_string(heuristic_time));
  RecordProperty("time_relaxed_s", std::to_string(relaxed.time_after));
  RecordProperty("evaluations", relaxed.evaluations);
  EXPECT_LT(heuristic_time, 0.9 * relaxed.time_before);          // the seed's idea pays
  EXPECT_LE(relaxed.time_after, heuristic_time * 1.001);          // and the optimum is at least as good
  EXPECT_LT(relaxed.time_after, 0.9 * relaxed.time_before);
  double tilt_at_crossing = 0, tilt_far = 0;
  for (std::size_t i = 0; i < n; ++i) {
    EXPECT_GE(relaxed.orientation[i].tilt, settings.tilt_min - 1e-12);
    EXPECT_LE(relaxed.orientation[i].tilt, settings.tilt_max + 1e-12);
    const double x = pass.points[i].contact.x();
    if (std::abs(x) < 0.2) tilt_at_crossing = relaxed.orientation[i].tilt;
    if (std::abs(x + 28) < 0.2) tilt_far = relaxed.orientation[i].tilt;
    // The guide surface is kept: the corner circle's nearest centre is S + r n for every pose.
    const machine::ClPose& pose = relaxed.poses[i];
    const Eigen::Vector3d centre = pose.tip + tool.corner_radius * pose.axis;
    Eigen::Vector3d radial = pass.points[i].contact - centre;
    radial -= pose.axis * pose.axis.dot(radial);
    EXPECT_LE((centre + (tool.radius - tool.corner_radius) * radial.normalized() - (pass.points[i].contact + tool.corner_radius * pass.points[i].normal)).norm(), 1e-9);
    EXPECT_NEAR(relaxed.effective_radius[i], tool.corner_radius, 1e-9);  // tilted across the feed: the scallop is the corner's
    EXPECT_TRUE(std::isinf(relaxed.gouge_margin[i]));              // convex across the feed: no gouge
  }
  EXPECT_GT(tilt_at_crossing, programmed[n / 2].tilt + 0.25 * kDeg);  // the tilt is raised where C saturated
  RecordProperty("tilt_at_crossing_deg", std::to_string(tilt_at_crossing / kDeg));
  RecordProperty("tilt_far_deg", std::to_string(tilt_far / kDeg));
}
