// The whole copy (Makki 2009's Fig. 3.30) on a part with an undercut: a femur-head-like ball on a
// neck (check 4, second part). Packets found by the pipeline cover >= 95 % of the points, one
// direction cannot, and no packet's roughing path enters the cloud or the stock's base with the whole
// tool (cutter, shank, holder), every position along every move checked. The finishing paths of the
// tilted packets do not pass that check yet (docs/clouds.md §4): DISABLED_ below states the goal.
#include "machine/machine_definition.hpp"
#include "paths/copy/cloud_copy.hpp"
#include "tests/paths/copy/test_clouds.hpp"

#include <gtest/gtest.h>

#include <cstdio>

namespace {

using namespace drom::paths;

TEST(CloudCopy, FemurHeadOnANeckIsCoveredByFewPacketsAndRoughedWithNoCollision) {
  const auto part = drom::tests::femur_head(20, 9, 45, 1.0);
  drom::geometry::PointCloud cloud;
  cloud.origin = "femur head";
  cloud.points = part.points, cloud.normals = part.normals;
  // The seed's hip settings (ball D6 on a D53 holder 40 mm out, 216 directions, [5, 85]) with the
  // exact normals, coarser paths (a test, not a part).
  CopySettings s = read_copy_settings("", "<defaults>",
                                      {"normals.from_file=true", "finishing.step=0.6", "finishing.scallop=0.02", "roughing.longitudinal_step=3", "roughing.transverse_step=4",
                                       "roughing.depth=6", "packets.max_packets=4"});
  const drom::machine::Machine m = drom::machine::load_machine(s.machine);
  const drom::machine::Kinematics kin(m);
  const CopyResult r = copy_cloud(cloud, s, kin);
  const int n = static_cast<int>(r.row_points.size());
  int best = 0;
  for (int j = 0; j < static_cast<int>(r.visibility.columns.size()); ++j) best = std::max(best, r.visibility.column_count(j));
  std::printf("femur head: %d points, %zu obstacle points; one direction covers at best %d (%.1f %%)\n", n, r.obstacle_points, best, 100.0 * best / n);
  std::printf("  %zu packets (%s): covered %d (%.1f %%), overlap %d, re-attached %d, unmachinable %d\n", r.packets.directions.size(), r.packets.method.c_str(),
              r.packets.covered, 100.0 * r.packets.covered / n, r.packets.overlaps, r.packets.reattached, r.packets.unmachinable);
  EXPECT_LT(best, 0.95 * n);
  ASSERT_GE(r.packets.directions.size(), 2u);
  EXPECT_TRUE(r.packets.coverage_met);
  // 95 % of the machinable points (issue 45: those some direction the machine reaches sees with the
  // whole tool clear; the rest of the ball's underside is out of the holder's reach).
  EXPECT_GE(r.packets.covered, 0.95 * r.packets.machinable);
  for (std::size_t k = 0; k < r.plans.size(); ++k) {
    const PacketPlan& p = r.plans[k];
    EXPECT_TRUE(p.error.empty()) << p.error;
    ASSERT_TRUE(p.finishing && p.roughing);
    std::printf("  packet %zu: axis (%.3f %.3f %.3f), rotary (%.1f, %.1f) deg, %d points; finishing %zu points, gaps %lld, deepest %.4f mm (%lld positions); "
                "roughing %zu points, deepest %.4f mm (%lld positions); cycle %.0f + %.0f s\n",
                k + 1, p.axis.x(), p.axis.y(), p.axis.z(), p.rotary.x(), p.rotary.y(), p.points, p.finish_op.path.size(), p.finishing->gaps, p.finish_op.check.deepest,
                p.finish_op.check.positions, p.rough_op.path.size(), p.rough_op.check.deepest, p.rough_op.check.positions, p.rough_op.cycle_time, p.finish_op.cycle_time);
    EXPECT_GT(p.finish_op.path.size(), 0u);
    EXPECT_EQ(p.rough_op.check.over, 0) << "roughing of packet " << k + 1 << " enters the cloud by " << p.rough_op.check.deepest << " mm";
    EXPECT_TRUE(p.finish_op.error.empty()) << p.finish_op.error;
    EXPECT_FALSE(p.finish_op.gcode.empty());
    EXPECT_GT(p.finish_op.cycle_time, 0);
    // The 3+2 program indexes the rotary axes once, to the packet's angles.
    EXPECT_NE(p.finish_op.gcode.find("A"), std::string::npos);
  }
}

TEST(CloudCopy, FemurHeadFinishingPathsClearTheCloudWithTheWholeTool) {
  const auto part = drom::tests::femur_head(20, 9, 45, 1.0);
  drom::geometry::PointCloud cloud;
  cloud.points = part.points, cloud.normals = part.normals;
  CopySettings s = read_copy_settings("", "<defaults>", {"normals.from_file=true", "finishing.step=0.6", "finishing.scallop=0.02", "roughing.enabled=false"});
  const drom::machine::Machine m = drom::machine::load_machine(s.machine);
  const CopyResult r = copy_cloud(cloud, s, drom::machine::Kinematics(m));
  for (std::size_t k = 0; k < r.plans.size(); ++k)
    EXPECT_EQ(r.plans[k].finish_op.check.over, 0) << "finishing of packet " << k + 1 << " enters the cloud by " << r.plans[k].finish_op.check.deepest << " mm";
}

}  // namespace
