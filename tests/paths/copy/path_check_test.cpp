// Issue 45, item 5: a posted move known to leave the tolerance is a refusal naming where, not a number.
// A straight cut across a bump the planner never dropped on (as an unresolved chord would be) is found
// by the whole-tool check, and refused with its deepest position in the part frame; the same ground
// crossed above the bump is not.
#include "geometry/cloud_bins.hpp"
#include "paths/copy/path_check.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <string>
#include <vector>

namespace {

using drom::paths::CloudPath;
using drom::paths::Motion;
using drom::paths::ToolAssembly;

// A level plate 40 x 40 mm sampled every 0.25 mm with a bump 2 mm high at the origin (drop frame).
std::vector<Eigen::Vector3d> plate_with_bump() {
  std::vector<Eigen::Vector3d> points;
  for (int i = -80; i <= 80; ++i)
    for (int j = -80; j <= 80; ++j) {
      const double x = 0.25 * i, y = 0.25 * j;
      points.emplace_back(x, y, 2 * std::exp(-(x * x + y * y) / 4));
    }
  return points;
}

}  // namespace

TEST(PathCheck, AMoveThroughTheScanIsRefusedNamingWhereInThePartFrame) {
  const std::vector<Eigen::Vector3d> points = plate_with_bump();
  const drom::geometry::CloudBins bins(points, 1.0);
  const ToolAssembly tool = ToolAssembly::ball(3, 12);
  const double tolerance = 0.01;
  // The packet's drop frame: the part turned 30 degrees about X (drop = frame * part).
  const double a = 30 * std::numbers::pi / 180;
  Eigen::Matrix3d frame;
  frame << 1, 0, 0, 0, std::cos(a), -std::sin(a), 0, std::sin(a), std::cos(a);

  CloudPath through;
  through.add({-15, 0, 0}, Motion::cut, 0);
  through.add({15, 0, 0}, Motion::cut, 0);
  const auto check = drom::paths::check_path(bins, through, tool, 0.1, tolerance);
  EXPECT_GT(check.over, 0);
  EXPECT_NEAR(check.deepest, 2, 0.05);       // the ball's tip at the bump's top, 2 mm under it
  EXPECT_NEAR(check.worst.x(), 0, 0.15);
  const std::string why = drom::paths::refusal(check, frame, tolerance);
  ASSERT_FALSE(why.empty());
  EXPECT_NE(why.find("not posted"), std::string::npos) << why;
  const Eigen::Vector3d part = frame.transpose() * check.worst;
  char where[96];
  std::snprintf(where, sizeof where, "(%.3f, %.3f, %.3f) in the part frame", part.x(), part.y(), part.z());
  EXPECT_NE(why.find(where), std::string::npos) << why;
  EXPECT_NE(why.find(std::to_string(check.over) + " tool positions"), std::string::npos) << why;

  CloudPath over;
  over.add({-15, 0, 0}, Motion::cut, 0);
  over.add({-15, 0, 2.5}, Motion::link);
  over.add({15, 0, 2.5}, Motion::link);
  over.add({15, 0, 0}, Motion::cut, 1);
  const auto clear = drom::paths::check_path(bins, over, tool, 0.1, tolerance);
  EXPECT_EQ(clear.over, 0) << "deepest " << clear.deepest;
  EXPECT_TRUE(drom::paths::refusal(clear, frame, tolerance).empty());
}
