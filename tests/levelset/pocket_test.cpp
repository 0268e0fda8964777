// Issue 3 checks 2-4: removal on a hex mesh converges; a generated pocket survives G-code; whole
// pockets remove their exact volume.
#include "fem/mesh_geometry.hpp"
#include "fem/structured_mesh.hpp"
#include "levelset/gcode.hpp"
#include "levelset/material_removal.hpp"
#include "paths/cutter/tool_assembly.hpp"
#include "levelset/pocket_toolpath.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace drom;
using namespace drom::levelset;
using drom::paths::ToolAssembly;
using drom::geometry::RemovalCriterion;
using drom::geometry::PartShape;

namespace {

double removed_volume(MaterialRemoval& removal, const Toolpath& path) {
  const PathTimeline timeline(path);
  removal.sweep(cutting_polylines(path, timeline, 0, timeline.length(), 0.01));
  return removal.removed_volume();
}

}  // namespace

TEST(Toolpath, OneWayPocketPassesTimelineAndScallop) {
  const PartShape plate = PartShape::plate(1000, 1000, 10);
  const ToolAssembly tool = ToolAssembly::flat(12.5, 30);
  const PocketSpec pocket{200, 200, 600, 600, 2};
  const auto passes = pass_positions(pocket, tool, 20);
  ASSERT_EQ(passes.size(), 30u);  // (600 - 25) / 20 + 1 = 29.75: the last pass follows the wall
  EXPECT_DOUBLE_EQ(passes.front(), 212.5);
  EXPECT_DOUBLE_EQ(passes.back(), 787.5);
  const Toolpath path = pocket_toolpath(plate, pocket, tool, {PocketStrategy::OneWay, 20, 10, 2, 5, 0.01});
  const PathTimeline timeline(path);
  // Position <-> time both ways, on a cutting move.
  const double t = 0.37 * timeline.duration();
  const Eigen::Vector3d p = timeline.position_at_time(t);
  if (path.moves[timeline.move_at_time(t)].cutting()) {
    EXPECT_NEAR(timeline.time_of(p), t, 1e-6);
  }
  EXPECT_NEAR(timeline.time_at_length(timeline.length_at_time(t)), t, 1e-9);
  // Cutting time: 30 passes of 575 mm at 10 mm/s and 31 plunges of 7 mm at 2 mm/s, then the wall
  // contour: 2 x 575 + 2 x 575 mm at 10 mm/s.
  double cutting = 0;
  for (const auto& m : path.moves)
    if (m.cutting()) cutting += m.length() / m.feed;
  EXPECT_NEAR(cutting, 30 * 57.5 + 31 * 3.5 + 4 * 57.5, 1e-6);
  // Scallop: h = R - sqrt(R^2 - s^2/4) for a ball; stepover_for_scallop inverts it.
  const ToolAssembly ball = ToolAssembly::ball(5, 20);
  EXPECT_NEAR(scallop_height(ball, 2.0), 5 - std::sqrt(25 - 1.0), 1e-12);
  EXPECT_NEAR(stepover_for_scallop(ball, scallop_height(ball, 2.0)), 2.0, 1e-9);
  const ToolAssembly bull = ToolAssembly::bull_nose(6, 2, 20);
  EXPECT_NEAR(scallop_height(bull, stepover_for_scallop(bull, 0.05)), 0.05, 1e-12);
  EXPECT_THROW(stepover_for_scallop(tool, 0.01), std::invalid_argument);
}

TEST(Removal, HexMeshDeactivatedVolumeConverges) {
  // A ball end mill pass (R 5, depth 2, 30 mm) through a 50 x 20 x 4 block meshed ever finer.
  const PartShape block = PartShape::plate(50, 20, 4);
  const ToolAssembly ball = ToolAssembly::ball(5, 20);
  MaterialRemoval removal(Workpiece::from_shape(block), ball, 0.05);
  removal.sweep({{{10, 10, 2}, {40, 10, 2}}});
  const double alpha = std::asin(3.0 / 5);
  const double exact = M_PI * 4 * 13 / 3 + 25 * 30 * (M_PI / 2 - alpha - std::sin(2 * alpha) / 2);
  // Two ways to turn the level set into element activity, at each element size: the centroid (the
  // seed's), and the volume fraction (drom's default), integrated on a voxel-fine lattice of each
  // element and so independent of the element size.
  double previous_centroid = 0;
  const int sizes[] = {5, 10, 20, 40};  // elements along 20 mm: h = 4, 2, 1, 0.5 mm
  for (int n : sizes) {
    const double h = 20.0 / n;
    const fem::Mesh mesh = fem::make_structured_hex_mesh(block, {n * 5 / 2, n, n / 5 < 1 ? 1 : n / 5, 1.0});
    const fem::MeshGeometry elements(mesh);
    const auto volumes = fem::element_volumes(mesh);
    double errors[2];
    for (int c = 0; c < 2; ++c) {
      std::vector<double> remaining;
      removal.update_remaining(elements, c == 0 ? RemovalCriterion::Centroid : RemovalCriterion::VolumeFraction, remaining, false);
      double gone = 0;
      for (std::size_t e = 0; e < remaining.size(); ++e) gone += (1 - remaining[e]) * volumes[e];
      errors[c] = std::abs(gone - exact) / exact;
    }
    std::printf("h = %.2f mm: relative volume error: centroid %.4f, volume fraction %.6f\n", h, errors[0], errors[1]);
    if (previous_centroid > 0) std::printf("   observed order of the centroid criterion: %.2f\n", std::log2(previous_centroid / errors[0]));
    EXPECT_LT(errors[1], errors[0]) << "volume fraction must be the more accurate at equal size (h = " << h << ")";
    EXPECT_LT(errors[1], 0.002) << h;
    if (previous_centroid > 0) {
      EXPECT_LT(errors[0], previous_centroid);
    }
    previous_centroid = errors[0];
  }
}

TEST(Removal, GCodeRoundTripGivesSameStationsAndVolumes) {
  const PartShape plate = PartShape::plate(120, 80, 10);
  const ToolAssembly tool = ToolAssembly::bull_nose(6, 1, 25);
  const PocketSpec pocket{20, 15, 80, 50, 2.5};
  const Toolpath path = pocket_toolpath(plate, pocket, tool, {PocketStrategy::Zigzag, 9, 10, 2, 5, 0.01});
  const Toolpath back = parse_gcode(write_gcode(path, "zigzag pocket"), "zigzag.nc");
  const PathTimeline t1(path), t2(back);
  const auto s1 = stations_by_spacing(path, t1, 10), s2 = stations_by_spacing(back, t2, 10);
  ASSERT_EQ(s1.size(), s2.size());
  for (std::size_t k = 0; k < s1.size(); ++k) {
    EXPECT_NEAR(s1[k].time, s2[k].time, 1e-3);
    EXPECT_LT((s1[k].position - s2[k].position).norm(), 1e-3);
  }
  MaterialRemoval r1(Workpiece::from_shape(plate), tool, 0.25), r2(Workpiece::from_shape(plate), tool, 0.25);
  for (std::size_t k = 0; k < s1.size(); ++k) {
    const double a0 = k ? s1[k - 1].path_length : 0, b0 = k ? s2[k - 1].path_length : 0;
    const double v1 = r1.sweep(cutting_polylines(path, t1, a0, s1[k].path_length, 0.01));
    const double v2 = r2.sweep(cutting_polylines(back, t2, b0, s2[k].path_length, 0.01));
    EXPECT_NEAR(v1, v2, 1e-3 * std::max(1.0, v1)) << "station " << k;
  }
  EXPECT_NEAR(r1.removed_volume(), r2.removed_volume(), 1e-3 * r1.removed_volume());
}

TEST(Removal, FlatPlatePocketRemovesItsVolume) {
  const PartShape plate = PartShape::plate(1000, 1000, 10);
  const ToolAssembly tool = ToolAssembly::flat(12.5, 30);
  const PocketSpec pocket{200, 200, 600, 600, 2};
  MaterialRemoval removal(Workpiece::from_shape(plate), tool, 0.5);
  const double v = removed_volume(removal, pocket_toolpath(plate, pocket, tool, {PocketStrategy::OneWay, 20, 10, 2, 5, 0.01}));
  const double exact = 600.0 * 600 * 2;
  const double corners = 4 * (1 - M_PI / 4) * 12.5 * 12.5 * 2;  // the tool's radius stays in the corners
  std::printf("flat-plate pocket: %.1f mm^3 vs %.1f (%.3f %%; corners account for %.3f %%)\n", v, exact, 100 * (v / exact - 1), -100 * corners / exact);
  EXPECT_NEAR(v / exact, 1.0, 0.005);
  EXPECT_NEAR(removal.measured_volume() / exact, 1.0, 0.01);  // OpenVDB's measure, on a 4-voxel-thick floor
}

TEST(Removal, CurvedPanelPocketRemovesItsExactVolume) {
  const double Ro = 1750, e = 4.5, d = 3;
  const PartShape panel = PartShape::panel(450, 450, e, Ro);
  const ToolAssembly tool = ToolAssembly::flat(8, 25);
  const PocketSpec pocket{75, 75, 300, 300, d};
  MaterialRemoval removal(Workpiece::from_shape(panel), tool, 0.3);
  const Toolpath path = pocket_toolpath(panel, pocket, tool, {PocketStrategy::OneWay, 8.4, 10, 2, 5, 0.01});
  const double v = removed_volume(removal, path);
  // Annular sector: the pocket spans 300 mm of outer arc, 300 mm along the axis, 3 mm radially.
  const double sector = 300.0 * 0.5 * (300.0 / Ro) * (Ro * Ro - (Ro - d) * (Ro - d));
  // A vertical flat end mill on a convex floor touches it with the edge nearer the crown, so next to
  // the curved end walls it cannot come down to the floor: integrate that envelope independently
  // (closed-form floor, brute-force minimum over the tool positions) along the curved direction.
  const double Rf = Ro - d, half_angle = 150.0 / Ro, xc = 225.0, z0 = Ro - e;
  auto floor_z = [&](double x) { return std::sqrt(Rf * Rf - (x - xc) * (x - xc)) - z0; };
  const double x_lo = xc + Rf * std::sin(-half_angle), x_hi = xc + Rf * std::sin(half_angle);
  auto tip_z = [&](double x) {  // highest floor point under the flat bottom
    double best = -1e9;
    for (int k = 0; k <= 400; ++k) best = std::max(best, floor_z(x - 8 + 16.0 * k / 400));
    return best;
  };
  const double first = xc + (Rf) * std::sin((83.0 - 225.0) / Ro), last = 2 * xc - first;  // tool centre range (u0 + R .. u1 - R)
  double unreachable = 0;
  const int n = 3000;
  for (int i = 0; i < n; ++i) {
    const double x = x_lo + (x_hi - x_lo) * (i + 0.5) / n;
    double envelope = 1e9;
    for (int k = 0; k <= 200; ++k) {
      const double c = std::clamp(x - 8 + 16.0 * k / 200, first, last);
      if (std::abs(c - x) <= 8) envelope = std::min(envelope, tip_z(c));
    }
    unreachable += std::max(0.0, envelope - floor_z(x)) * (x_hi - x_lo) / n;
  }
  unreachable *= 300.0 - 2 * 8 * (1 - M_PI / 4) * 0;  // along the axis (corner effects aside)
  const double exact = sector - unreachable;
  std::printf("curved-panel pocket: %.1f mm^3; sector %.1f, unreachable by a vertical flat tool %.1f (%.2f %%); error %.3f %%\n", v, sector,
              unreachable, 100 * unreachable / sector, 100 * (v / exact - 1));
  EXPECT_NEAR(v / exact, 1.0, 0.005);
}

TEST(Removal, SpiralAndZigzagPocketsClearThePocket) {
  const PartShape plate = PartShape::plate(160, 120, 10);
  const ToolAssembly tool = ToolAssembly::flat(6, 20);
  const PocketSpec pocket{30, 20, 100, 80, 1.5};
  const double exact = 100.0 * 80 * 1.5 - 4 * (1 - M_PI / 4) * 36 * 1.5;  // the corners keep the tool's radius
  for (auto strategy : {PocketStrategy::Spiral, PocketStrategy::Zigzag}) {
    MaterialRemoval removal(Workpiece::from_shape(plate), tool, 0.25);
    const Toolpath path = pocket_toolpath(plate, pocket, tool, {strategy, 10, 10, 2, 5, 0.01});
    const double v = removed_volume(removal, path);
    // The spiral's rings are its own wall contour; zigzag gets the finishing contour.
    EXPECT_NEAR(v / exact, 1.0, 0.005) << (strategy == PocketStrategy::Spiral ? "spiral" : "zigzag");
    // Every move stays inside the pocket (tool centre at least R from the walls).
    for (const auto& m : path.moves) {
      EXPECT_GE(m.end.x(), 30 + 6 - 1e-9);
      EXPECT_LE(m.end.x(), 130 - 6 + 1e-9);
      EXPECT_GE(m.end.y(), 20 + 6 - 1e-9);
      EXPECT_LE(m.end.y(), 100 - 6 + 1e-9);
    }
  }
}
