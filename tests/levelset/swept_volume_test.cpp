// Issue 3 check 1: the volume a straight pass removes, against closed forms (seed Annex C).
#include "levelset/material_removal.hpp"
#include "paths/cutter/tool_assembly.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace drom::levelset;
using drom::paths::ToolAssembly;
using drom::geometry::PartShape;

namespace {

// A pass of length D at depth h below the top of a 100 x 60 x 10 block, along x at y = 30.
double measured(const ToolAssembly& tool, double h, double D, double voxel, double* accumulated = nullptr) {
  MaterialRemoval removal(Workpiece::from_shape(PartShape::plate(100, 60, 10)), tool, voxel);
  removal.sweep({{{30, 30, 10 - h}, {30 + D, 30, 10 - h}}});
  if (accumulated) *accumulated = removal.removed_volume();
  return removal.measured_volume();
}

// Cross-section swept across the pass times D, plus the tool's solid of revolution below h.
double bull_nose_closed_form(double R, double r, double h, double D) {
  const double section = 2 * ((R - r) * h + r * (h - r) + M_PI * r * r / 4);
  const double revolution = M_PI * ((R - r) * (R - r) * r + (R - r) * M_PI * r * r / 2 + 2 * r * r * r / 3) + M_PI * R * R * (h - r);
  return section * D + revolution;
}

}  // namespace

TEST(SweptVolume, BallEndMillMatchesSeedAnnexC) {
  const double R = 5, h = 2, D = 30;
  const double alpha = std::asin((R - h) / R);
  const double exact = M_PI * h * h * (3 * R - h) / 3 + R * R * D * (M_PI / 2 - alpha - std::sin(2 * alpha) / 2);
  EXPECT_NEAR(exact, 390.1, 0.2);  // the seed's "about 390.1"; the closed form gives 389.93
  double accumulated = 0;
  const double v = measured(ToolAssembly::ball(R, 20), h, D, 0.1, &accumulated);
  std::printf("ball: exact %.2f, level set %.2f (%.3f %%), voxel sum %.2f (%.3f %%)\n", exact, v, 100 * (v / exact - 1), accumulated,
              100 * (accumulated / exact - 1));
  EXPECT_NEAR(v / exact, 1.0, 0.005);
  EXPECT_NEAR(accumulated / exact, 1.0, 0.005);
}

TEST(SweptVolume, FlatEndMillMatchesClosedForm) {
  const double R = 5, h = 2, D = 30;
  const double exact = h * (M_PI * R * R + 2 * R * D);
  const double v = measured(ToolAssembly::flat(R, 20), h, D, 0.1);
  std::printf("flat: exact %.2f, level set %.2f (%.3f %%)\n", exact, v, 100 * (v / exact - 1));
  EXPECT_NEAR(v / exact, 1.0, 0.005);
}

TEST(SweptVolume, BullNoseMatchesClosedForm) {
  const double R = 6, r = 2, h = 3, D = 30;
  const double exact = bull_nose_closed_form(R, r, h, D);
  EXPECT_NEAR(bull_nose_closed_form(5, 5, 5, 0), 2.0 / 3 * M_PI * 125, 1e-9);  // a ball at full depth: a half sphere
  const double v = measured(ToolAssembly::bull_nose(R, r, 20), h, D, 0.1);
  std::printf("bull-nose: exact %.2f, level set %.2f (%.3f %%)\n", exact, v, 100 * (v / exact - 1));
  EXPECT_NEAR(v / exact, 1.0, 0.005);
}

TEST(SweptVolume, SecondPassOverRemovedMaterialRemovesNothing) {
  MaterialRemoval removal(Workpiece::from_shape(PartShape::plate(100, 60, 10)), ToolAssembly::flat(5, 20), 0.2);
  const std::vector<std::vector<Eigen::Vector3d>> pass{{{30, 30, 8}, {60, 30, 8}}};
  const double first = removal.sweep(pass);
  EXPECT_GT(first, 500);
  EXPECT_NEAR(removal.sweep(pass), 0.0, 1e-9);
  // A plunge (vertical move) and a ramp go through the general swept distance.
  const double plunge = removal.sweep({{{80, 30, 11}, {80, 30, 8}}});
  EXPECT_NEAR(plunge / (M_PI * 25 * 2), 1.0, 0.01);
}

TEST(ToolGeometry, SignedDistanceOfEachKind) {
  const ToolAssembly ball = ToolAssembly::ball(5, 20), flat = ToolAssembly::flat(5, 20), bull = ToolAssembly::bull_nose(5, 2, 20);
  EXPECT_NEAR(ball.signed_distance(0, 0), 0, 1e-12);
  EXPECT_NEAR(ball.signed_distance(0, 5), -5, 1e-12);
  EXPECT_NEAR(ball.signed_distance(8, 5), 3, 1e-12);
  EXPECT_NEAR(flat.signed_distance(0, -1), 1, 1e-12);
  EXPECT_NEAR(flat.signed_distance(6, 10), 1, 1e-12);
  EXPECT_NEAR(bull.signed_distance(3, 0), 0, 1e-12);        // flat part of the bottom
  EXPECT_NEAR(bull.signed_distance(5, 2), 0, 1e-12);        // end of the corner arc
  EXPECT_NEAR(bull.bottom_height(5), 2, 1e-12);
  EXPECT_NEAR(ball.section_radius(5), 5, 1e-12);
  EXPECT_NEAR(bull.section_radius(0), 3, 1e-12);
}
