// Check 4 of the point-cloud issue: the visibility matrix and the packets. The seed's synthetic
// hemisphere (2 537 points, exact normals, 648 directions, [10, 80] degrees, ball D10, the
// table-table machine with A in [-30, 120] degrees) needs two packets; a femur-head-like ball on a
// neck (an undercut) is covered by the fewest packets found.
#include "machine/kinematics.hpp"
#include "machine/machine_definition.hpp"
#include "paths/copy/packets.hpp"
#include "paths/copy/sphere_normals.hpp"
#include "paths/copy/visibility.hpp"
#include "tests/paths/copy/test_clouds.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace {

using namespace drom::paths;
constexpr double kDegree = std::numbers::pi / 180;

drom::machine::Kinematics seed_machine() { return drom::machine::Kinematics(drom::machine::load_machine("ucp710_like", {"axes.A.stroke=[-30, 120]"})); }

TEST(Visibility, DirectionGridHasTheSeedsCounts) {
  EXPECT_EQ(direction_grid(10, 10).grid_count, 648);
  EXPECT_EQ(direction_grid(10, 30).grid_count, 216);
  EXPECT_EQ(direction_grid(10, 10).unit.size(), 648u - 35u);  // the pole once
  for (const auto& d : direction_grid(10, 30).unit) EXPECT_NEAR(d.norm(), 1, 1e-15);
}

TEST(Visibility, MachineReachIsTheTableTablesCone) {
  // A = acos(k) on the branch within [-30, 120]: reachable iff k >= cos 120 = -0.5 (the digest's
  // derivation); the hip's orientation [0 0.9848 0.1736] at A = 80 degrees.
  const auto kin = seed_machine();
  const Eigen::Vector3d lo(-40, -40, 0), hi(40, 40, 40);
  for (const auto& d : direction_grid(10, 10).unit) EXPECT_EQ(machine_reach(kin, d, lo, hi, false).ok, d.z() >= -0.5 - 1e-9) << d.transpose();
  const Reach hip = machine_reach(kin, Eigen::Vector3d(0, 0.9848, 0.1736).normalized(), lo, hi, false);
  ASSERT_TRUE(hip.ok);
  EXPECT_NEAR(std::abs(hip.rotary.x()), 80, 0.01);
  const Reach below = machine_reach(kin, Eigen::Vector3d(0.3, 0, -0.9).normalized(), lo, hi, false);
  EXPECT_FALSE(below.ok);
  EXPECT_NE(below.why.find("beyond its stroke"), std::string::npos) << below.why;
  // The Z travel with a long tool: the gauge line above the stroke's top at the box's highest corner.
  const auto tall = drom::machine::Kinematics(drom::machine::load_machine("ucp710_like", {"setup.tool_length=480"}));
  EXPECT_FALSE(machine_reach(tall, Eigen::Vector3d::UnitZ(), lo, hi, true).ok);
  EXPECT_TRUE(machine_reach(tall, Eigen::Vector3d::UnitZ(), lo, hi, false).ok);
}

TEST(Visibility, BodyCollisionsOnAConvexAndAConcaveShape) {
  // Outside a sphere nothing hits the body whatever the tilt within the window; at the bottom of a
  // narrow bowl the shank hits the rim once the tool tilts.
  const auto ball = drom::tests::seed_hemisphere();
  ToolAssembly tool;
  tool.cutter = {ToolKind::ball, 5, 5};
  for (const double tilt : {0.0, 40.0, 79.0}) {
    const Eigen::Vector3d p = ball.points[1000], n = ball.normals[1000];
    const Eigen::Vector3d side = n.cross(Eigen::Vector3d::UnitZ()).normalized();
    const Eigen::Vector3d d = std::cos(tilt * kDegree) * n + std::sin(tilt * kDegree) * side.cross(n);
    EXPECT_TRUE(BodyCheck(ball.points, d, tool, 0.01).clear(p, n)) << tilt;
  }
  std::vector<Eigen::Vector3d> bowl;  // a cylinder hole of radius 8, 30 deep, with a floor
  for (int k = 0; k < 360; ++k)
    for (int z = 0; z <= 30; ++z) bowl.emplace_back(8 * std::cos(k * kDegree), 8 * std::sin(k * kDegree), z);
  for (int i = -7; i <= 7; ++i)
    for (int j = -7; j <= 7; ++j) bowl.emplace_back(i, j, 0);
  const Eigen::Vector3d bottom(0, 0, 0), up = Eigen::Vector3d::UnitZ();
  EXPECT_TRUE(BodyCheck(bowl, up, tool, 0.01).clear(bottom, up));
  EXPECT_FALSE(BodyCheck(bowl, Eigen::Vector3d(std::sin(30 * kDegree), 0, std::cos(30 * kDegree)), tool, 0.01).clear(bottom, up));
  // The holder: a 53 mm holder 40 mm up clears a lone post 20 mm away only if the post is lower than the holder's face.
  tool.gauge_length = 40, tool.holder = RevolvedProfile::endless_cylinder(26.5);
  std::vector<Eigen::Vector3d> post = {{20, 0, 30}};
  EXPECT_TRUE(BodyCheck(post, up, tool, 0.01).clear(bottom, up));
  post.front().z() = 50;
  EXPECT_FALSE(BodyCheck(post, up, tool, 0.01).clear(bottom, up));
}

TEST(Packets, SeedHemisphereNeedsTwoPackets) {
  const auto hemisphere = drom::tests::seed_hemisphere();
  ASSERT_EQ(hemisphere.points.size(), 2537u);
  const auto kin = seed_machine();
  VisibilitySettings v;
  v.phi_step = 10, v.theta_step = 10, v.cone_min = 10, v.cone_max = 80;
  v.tool.cutter = {ToolKind::ball, 5, 5};
  v.machine = &kin;
  v.check_travel = false;
  const VisibilityMatrix m = visibility_matrix(hemisphere.points, hemisphere.points, hemisphere.normals, v);
  int reachable = 0, seen = 0;
  for (std::size_t j = 0; j < m.reachable.size(); ++j) {
    reachable += m.reachable[j];
    seen += m.column_count(static_cast<int>(j)) > 0;
  }
  // One direction: none covers 95 % (+Z misses the apex, under 10 degrees, and the rim, over 80).
  int best = 0, best_count = 0;
  for (int j = 0; j < static_cast<int>(m.reachable.size()); ++j)
    if (m.column_count(j) > best_count) best = j, best_count = m.column_count(j);
  std::printf("hemisphere: %d directions (%d distinct), %d reachable, %d see some point; %lld bits in the tool cones, %lld cleared by collisions\n",
              m.directions.grid_count, static_cast<int>(m.directions.unit.size()), reachable, seen, m.tool_visible, m.collisions);
  std::printf("  one direction: best (%.3f %.3f %.3f) covers %d of 2537 (%.1f %%)\n", m.directions.unit[static_cast<std::size_t>(best)].x(),
              m.directions.unit[static_cast<std::size_t>(best)].y(), m.directions.unit[static_cast<std::size_t>(best)].z(), best_count, 100.0 * best_count / 2537);
  EXPECT_LT(best_count, 0.95 * 2537);
  EXPECT_EQ(m.collisions, 0);  // a convex part: nothing hits the body
  const auto reaches = [&](int i, int j) { return m.directions.unit[static_cast<std::size_t>(j)].dot(hemisphere.normals[static_cast<std::size_t>(i)]) >= 0; };
  PacketSettings settings;
  settings.coverage = 0.95;  // the seed's pa
  const Packets p = group_packets(m, hemisphere.points, hemisphere.normals, settings, reaches);
  ASSERT_EQ(p.directions.size(), 2u);
  EXPECT_TRUE(p.coverage_met);
  const Eigen::Vector3d a = m.directions.unit[static_cast<std::size_t>(p.directions[0])], b = m.directions.unit[static_cast<std::size_t>(p.directions[1])];
  std::printf("  two packets (%s, %lld pairs examined): (%.3f %.3f %.3f) and (%.3f %.3f %.3f); covered %d (%.1f %%), overlap %d, re-attached %d, unmachinable %d; sizes %d + %d\n",
              p.method.c_str(), p.combinations, a.x(), a.y(), a.z(), b.x(), b.y(), b.z(), p.covered, 100.0 * p.covered / 2537, p.overlaps, p.reattached, p.unmachinable,
              p.sizes()[0], p.sizes()[1]);
  EXPECT_GE(p.covered, static_cast<int>(std::ceil(0.95 * 2537)));
  // The rest re-attached (the seed: "all points after reintegration") but a few rim points the less
  // tilted pair faces away from (issue 45's rule puts the tilt before the seed's fewest overlaps).
  EXPECT_LE(p.unmachinable, 5);
  // The seed's pair, +-30 degrees about Y, covers as much but overlaps far more on this cloud.
  int plus = -1, minus = -1;
  for (int j = 0; j < static_cast<int>(m.directions.unit.size()); ++j) {
    if ((m.directions.unit[static_cast<std::size_t>(j)] - Eigen::Vector3d(0.5, 0, std::sqrt(0.75))).norm() < 1e-9) plus = j;
    if ((m.directions.unit[static_cast<std::size_t>(j)] - Eigen::Vector3d(-0.5, 0, std::sqrt(0.75))).norm() < 1e-9) minus = j;
  }
  ASSERT_GE(plus, 0);
  ASSERT_GE(minus, 0);
  int cover = 0, both = 0;
  for (int i = 0; i < m.points; ++i) cover += m.test(i, plus) || m.test(i, minus), both += m.test(i, plus) && m.test(i, minus);
  std::printf("  the seed's pair (+-0.5 0 0.866): covers %d (%.1f %%), overlap %d\n", cover, 100.0 * cover / 2537, both);
  std::printf("  chosen by the rule (issue 45): largest tilt %.0f deg, sum %.0f deg, decided by %s among %d tied\n", p.largest_tilt, p.tilt_sum, p.decided_by.c_str(), p.tied);
  // Issue 45's rule, checked by brute force over every pair apart from the grouping's code: no pair
  // that covers 95 % of the machinable points tilts less (largest, then sum), and the seed's pair,
  // admissible, tilts no less than the choice.
  const int machinable = p.machinable, target = static_cast<int>(std::ceil(0.95 * machinable - 1e-9));
  const auto tilt = [&](int j) { return std::acos(std::clamp(m.directions.unit[static_cast<std::size_t>(j)].z(), -1.0, 1.0)) / kDegree; };
  double best_largest = 1e9, best_sum = 1e9;
  for (int j = 0; j < static_cast<int>(m.directions.unit.size()); ++j)
    for (int k = j + 1; k < static_cast<int>(m.directions.unit.size()); ++k) {
      if (!m.reachable[static_cast<std::size_t>(j)] || !m.reachable[static_cast<std::size_t>(k)]) continue;
      int c = 0;
      for (int i = 0; i < m.points; ++i) c += m.test(i, j) || m.test(i, k);
      if (c < target) continue;
      const double largest = std::max(tilt(j), tilt(k)), sum = tilt(j) + tilt(k);
      if (largest < best_largest - 1e-6 || (std::abs(largest - best_largest) <= 1e-6 && sum < best_sum - 1e-6)) best_largest = largest, best_sum = sum;
    }
  EXPECT_NEAR(p.largest_tilt, best_largest, 1e-6);
  EXPECT_NEAR(p.tilt_sum, best_sum, 1e-6);
  EXPECT_LE(p.largest_tilt, 30 + 1e-6);
}

// Issue 45: the rule that chooses the packets, each criterion deciding once, on visibility matrices
// made by hand (a flat strip 100 x 10 mm of points, normals +Z; which direction sees which point is
// set here, not computed), with the grid's directions (10 x 30 degrees).
struct HandMatrix {
  std::vector<Eigen::Vector3d> points, normals;
  VisibilityMatrix m;
  explicit HandMatrix(int nx = 100, int ny = 10) {
    for (int i = 0; i < nx; ++i)
      for (int j = 0; j < ny; ++j) points.emplace_back(i + 0.5, j + 0.5, 0), normals.emplace_back(0, 0, 1);
    m.directions = direction_grid(10, 30);
    m.points = static_cast<int>(points.size());
    m.columns.assign(m.directions.unit.size(), std::vector<std::uint64_t>((points.size() + 63) / 64, 0));
    m.reachable.assign(m.directions.unit.size(), 1);
    m.rotary.assign(m.directions.unit.size(), Eigen::Vector2d::Zero());
  }
  int direction(double theta, double phi) const {
    for (std::size_t j = 0; j < m.directions.unit.size(); ++j)
      if (std::abs(m.directions.theta[j] - theta) < 1e-9 && (theta == 0 || std::abs(m.directions.phi[j] - phi) < 1e-9)) return static_cast<int>(j);
    return -1;
  }
  // Direction (theta, phi) sees the points whose x lies in [x0, x1).
  void sees(double theta, double phi, double x0, double x1) {
    const int j = direction(theta, phi);
    for (std::size_t i = 0; i < points.size(); ++i)
      if (points[i].x() >= x0 && points[i].x() < x1) m.columns[static_cast<std::size_t>(j)][i >> 6] |= std::uint64_t{1} << (i & 63);
  }
  Packets group() const {
    return group_packets(m, points, normals, {}, [](int, int) { return false; });
  }
  Eigen::Vector3d axis(const Packets& p, std::size_t k) const { return m.directions.unit[static_cast<std::size_t>(p.directions[k])]; }
};

TEST(PacketRule, FewestPacketsDecideBeforeTilt) {
  // One direction at 60 degrees sees the whole strip; the vertical and one at 30 degrees see half
  // each. One packet, tilted, before two that tilt less.
  HandMatrix h;
  h.sees(60, 0, 0, 100);
  h.sees(0, 0, 0, 50);
  h.sees(30, 90, 50, 100);
  const Packets p = h.group();
  ASSERT_EQ(p.directions.size(), 1u);
  EXPECT_NEAR(tilt_from_z(h.axis(p, 0)), 60, 1e-9);
  EXPECT_EQ(p.decided_by, "coverage");  // the only single direction that covers as much
}

TEST(PacketRule, LeastTiltDecidesAmongSetsThatCoverAsMuch) {
  // The cap of issue 45: the vertical sees 99.5 % of the points (not the top, under the seed's hollow
  // cone), a direction at 30 degrees all of them. Both cover as much (99 %): the vertical, a 3-axis job.
  HandMatrix h;
  h.sees(0, 0, 1, 100);  // all but the first column of points (10 of 1000)
  h.sees(30, 180, 0, 100);
  const Packets p = h.group();
  ASSERT_EQ(p.directions.size(), 1u);
  EXPECT_NEAR(h.axis(p, 0).z(), 1, 1e-12);
  EXPECT_EQ(p.decided_by, "least tilt");
  EXPECT_EQ(p.reattached + p.unmachinable, 10);
}

TEST(PacketRule, ShortestCycleDecidesBetweenEqualTilts) {
  // A strip 10 mm along X, 100 mm along Y. Two directions at 30 degrees see all of it, one leaning
  // towards +Y, one towards +X. In both drop frames the passes run along X (10 mm: short passes,
  // where the turns weigh); leaning towards +Y, they are stepped over the strip's length
  // foreshortened by cos 30: 14 % fewer passes and turns, the shorter cycle.
  HandMatrix h(10, 100);
  h.sees(30, 0, 0, 100);
  h.sees(30, 90, 0, 100);
  const Packets p = h.group();
  ASSERT_EQ(p.directions.size(), 1u);
  EXPECT_EQ(p.decided_by, "shortest cycle");
  EXPECT_NEAR(h.axis(p, 0).y(), 0.5, 1e-9);
}

TEST(PacketRule, FewestOverlapsDecideLast) {
  // Two pairs tilt alike and cost alike by the floor (within its 2 %); one sees the strip's middle
  // twice (an overlap, where witness lines would be): the other is chosen.
  HandMatrix h;
  h.sees(30, 60, 0, 60);
  h.sees(30, 300, 40, 100);   // with (30, 60): overlap on [40, 60)
  h.sees(30, 120, 0, 50);
  h.sees(30, 240, 50, 100);   // with (30, 120): no overlap; mirror images of the first pair, the same cycle
  const Packets p = h.group();
  ASSERT_EQ(p.directions.size(), 2u);
  EXPECT_EQ(p.overlaps, 0);
  EXPECT_EQ(p.decided_by, "fewest overlaps");
}

}  // namespace
