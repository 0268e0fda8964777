// Z-level roughing on a cloud's voxel map: a block with a closed pocket (the seed's Fig. 2.8, which
// its unchecked ramps cannot rough). Every position of the tool keeps the allowance over every point
// of the cloud; the pocket is entered by checked zigzag ramps, the outside from the side; nothing is
// plunged; the seed's straight ramp would have hit the pocket's wall.
#include "geometry/cloud_bins.hpp"
#include "geometry/cloud_voxel_map.hpp"
#include "paths/copy/cloud_roughing.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

namespace {

using namespace drom::paths;

// A 60 x 60 block, top at z = 0, sides down to -12, with a 24 x 24 pocket 10 deep in its middle.
std::vector<Eigen::Vector3d> pocket_block() {
  std::vector<Eigen::Vector3d> p;
  const double h = 0.5;
  for (double x = -30; x <= 30 + 1e-9; x += h)
    for (double y = -30; y <= 30 + 1e-9; y += h) p.emplace_back(x, y, std::abs(x) < 12 && std::abs(y) < 12 ? -10.0 : 0.0);
  for (double z = -10; z <= 0; z += h)
    for (double t = -12; t <= 12 + 1e-9; t += h) p.emplace_back(t, -12, z), p.emplace_back(t, 12, z), p.emplace_back(-12, t, z), p.emplace_back(12, t, z);
  for (double z = -12; z <= 0; z += h)
    for (double t = -30; t <= 30 + 1e-9; t += h) p.emplace_back(t, -30, z), p.emplace_back(t, 30, z), p.emplace_back(-30, t, z), p.emplace_back(30, t, z);
  return p;
}

TEST(CloudRoughing, PocketIsRoughedByCheckedRampsWithoutTouchingTheCloud) {
  const auto cloud = pocket_block();
  CloudRoughingSettings s;
  s.tool.cutter = {ToolKind::torus, 5, 0};  // the seed's flat D10
  s.longitudinal_step = 1.5, s.transverse_step = 3, s.depth = 2, s.allowance = 0.5, s.ramp_angle = 3;
  const drom::geometry::CloudVoxelMap map(cloud, roughing_voxel(s));
  drom::geometry::Box3 stock;
  stock.lo = Eigen::Vector3d(-36, -36, -12), stock.hi = Eigen::Vector3d(36, 36, 6);
  const Eigen::Matrix3d q = Eigen::Matrix3d::Identity();
  const CloudRoughing r = plan_cloud_roughing(map, q, stock, CloudArea::rectangle(-40, 40, -40, 40), -10, s);
  std::printf("pocket block: %zu voxels of %.2f mm, %d layers (%.1f to %.1f), %lld of %lld stock nodes cut, %lld blocked, %lld left unreachable;\n"
              "  %d segments: %d side entries, %d straight ramps, %d zigzag ramps, %d skipped; %d links, %d retracts; inflation %.2f mm\n",
              r.voxels, r.voxel, r.layers, r.top, r.bottom, r.cut, r.nodes, r.blocked, r.unreachable, r.segments, r.side_entries, r.ramps, r.zigzag_ramps, r.skipped_segments,
              r.links, r.retracts, r.inflation);
  EXPECT_EQ(r.layers, 8);  // from 6 down to -10 by 2
  EXPECT_GT(r.side_entries, 0);
  EXPECT_GT(r.zigzag_ramps + r.ramps, 0);
  // Every position along every feed move keeps the allowance over every point within the tool's radius.
  const drom::geometry::CloudBins bins(cloud, 1.0);
  double closest = 1e300;
  bool pocket_cut = false;
  const double tan_ramp = std::tan(s.ramp_angle * std::numbers::pi / 180);
  for (std::size_t i = 1; i < r.path.size(); ++i) {
    if (r.path.motion[i] == Motion::rapid) continue;
    const Eigen::Vector3d a = r.path.tips[i - 1], b = r.path.tips[i];
    for (int k = 0; k <= 20; ++k) {
      const Eigen::Vector3d p = a + (b - a) * (k / 20.0);
      closest = std::min(closest, p.z() - bins.max_z_within(p.x(), p.y(), s.tool.cutter.radius));
      if (std::abs(p.x()) < 6 && std::abs(p.y()) < 6 && p.z() < -5) pocket_cut = true;
    }
    // No plunge: a descent at the feed below the previous layer is a ramp no steeper than the angle
    // (the approach from above the layer, down an open column, comes right after a rapid).
    if (b.z() < a.z() - 1e-9 && r.path.motion[i - 1] != Motion::rapid) {
      EXPECT_LE(a.z() - b.z(), (b - a).head<2>().norm() * tan_ramp + 1e-9) << i;
    }
  }
  std::printf("  closest approach to the cloud over the tool's footprint: %.3f mm (allowance %.1f)\n", closest, s.allowance);
  EXPECT_GE(closest, s.allowance - 1e-9);
  EXPECT_TRUE(pocket_cut);
  // The seed's straight 3-degree ramp from a pocket segment's start runs 38 mm: through the wall.
  const double run = s.depth / tan_ramp;
  EXPECT_GT(run, 24 - 2 * s.tool.cutter.radius);
}

}  // namespace
