// The independent checker of issue 45 judged on moves whose answer is known by hand: a ball of radius
// 3 over a flat plate of points at z = 0, so the depth of any pose is 0 - (tip z) where the ball's
// lowest point stands over the plate. It must see a feed move too deep, pass one within Tu, fail a
// rapid that drags the tool through the material, and pass a retract straight out of a contact.
#include "tests/paths/copy/independent_checker.hpp"

#include <gtest/gtest.h>

using namespace drom::tests;

namespace {

std::vector<Eigen::Vector3d> plate() {
  std::vector<Eigen::Vector3d> p;
  for (int i = -40; i <= 40; ++i)
    for (int j = -40; j <= 40; ++j) p.emplace_back(0.25 * i, 0.25 * j, 0.0);
  return p;
}

checker::ToolSpec ball() {
  checker::ToolSpec t;
  t.kind = checker::ToolSpec::Kind::ball, t.radius = 3, t.corner = 3;
  return t;
}

checker::ClFile moves(std::vector<Eigen::Vector3d> tips, std::vector<char> rapid) {
  checker::ClFile cl;
  cl.tips = std::move(tips), cl.rapid = std::move(rapid);
  return cl;
}

constexpr double kTu = 0.01;

}  // namespace

TEST(IndependentChecker, MeasuresAFeedMoveIntoAPlateByItsTipDepth) {
  const auto pts = plate();
  const auto deep = checker::check_path(moves({{-2, 0, -0.05}, {2, 0, -0.05}}, {1, 0}), ball(), pts, pts, kTu);
  EXPECT_EQ(deep.over_cloud, 1);
  EXPECT_NEAR(deep.deepest_cloud, 0.05, 1e-6);
  EXPECT_NEAR(deep.deepest_truth, 0.05, 1e-6);
  const auto within = checker::check_path(moves({{-2, 0, -0.004}, {2, 0, -0.004}}, {1, 0}), ball(), pts, pts, kTu);
  EXPECT_EQ(within.over_cloud, 0);
  EXPECT_EQ(within.over_truth, 0);
  EXPECT_NEAR(within.deepest_cloud, 0.004, 1e-6);
}

TEST(IndependentChecker, PassesARetractStraightOutOfTheContactButNotARapidThatStaysIn) {
  const auto pts = plate();
  // A cut 0.004 deep (within Tu), then a rapid straight up the axis: the rapid leaves the contact.
  const auto retract = checker::check_path(moves({{-2, 0, -0.004}, {0, 0, -0.004}, {0, 0, 10}}, {1, 0, 1}), ball(), pts, pts, kTu);
  EXPECT_EQ(retract.over_cloud, 0);
  EXPECT_EQ(retract.over_truth, 0);
  // The same cut, then a rapid that runs on sideways at that depth: the tool scrapes the plate at rapid.
  const auto scrape = checker::check_path(moves({{-2, 0, -0.004}, {0, 0, -0.004}, {2, 0, -0.004}}, {1, 0, 1}), ball(), pts, pts, kTu);
  EXPECT_EQ(scrape.over_cloud, 1);
  EXPECT_EQ(scrape.over_truth, 1);
  // A rapid that does not leave a cut is held to no depth at all, from its first point.
  const auto plunge = checker::check_path(moves({{0, 0, 10}, {0, 0, -0.004}}, {1, 1}), ball(), pts, pts, kTu);
  EXPECT_EQ(plunge.over_cloud, 1);
}
