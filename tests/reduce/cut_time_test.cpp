// The cut-time index answers what the brute-force scan of the path answers, also when the path is far
// larger than the tool (finding 19 in docs/robustness.md: a path spanning 1e6 mm with a 1 µm tool
// asked for a bucket grid past an int).
#include "reduce/cut_time.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace {

using drom::reduce::CutTimeIndex;
using drom::reduce::first_cover_time;

// A zigzag of `passes` passes along x at z = 0, spanning `span` mm, one time unit per pass.
Eigen::MatrixXd zigzag(int passes, double span, double step) {
  Eigen::MatrixXd path(2 * passes, 4);
  for (int k = 0; k < passes; ++k) {
    const double y = k * step, t = 2.0 * k;
    path.row(2 * k) << (k % 2 ? span : 0.0), y, 0, t;
    path.row(2 * k + 1) << (k % 2 ? 0.0 : span), y, 0, t + 1;
  }
  return path;
}

void expect_same_as_scan(const Eigen::MatrixXd& path, double radius, const std::vector<Eigen::Vector3d>& points) {
  const CutTimeIndex index(path, radius, 0.01, 1.0);
  for (const auto& p : points) {
    const double scan = first_cover_time(path, {}, p, radius, 0.01), fast = index.at(p);
    if (std::isinf(scan)) EXPECT_TRUE(std::isinf(fast)) << p.transpose();
    else EXPECT_NEAR(fast, scan, 1e-9 * std::max(1.0, std::abs(scan))) << p.transpose();
  }
}

TEST(CutTimeIndex, AgreesWithTheScanOnAPocketSizedPath) {
  const Eigen::MatrixXd path = zigzag(20, 200, 8);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> x(-20, 220), y(-20, 180);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 2000; ++i) points.emplace_back(x(rng), y(rng), 0);
  expect_same_as_scan(path, 5, points);
}

TEST(CutTimeIndex, APathFarLargerThanTheToolStillIndexesAndAnswersLikeTheScan) {
  // 1e6 mm passes with a 1 µm tool: 2e12 cells of the radius's size; the grid is capped instead.
  const Eigen::MatrixXd path = zigzag(4, 1e6, 1e5);
  std::vector<Eigen::Vector3d> points = {{0, 0, 0}, {5e5, 0, 0}, {5e5, 5e-7, 0}, {5e5, 2e-6, 0}, {1e6, 1e5, 0}, {3.3e5, 2e5, 0}, {-1e7, 0, 0}, {1e300, -1e300, 0}};
  expect_same_as_scan(path, 1e-6, points);
  const CutTimeIndex index(path, 1e-6, 0.01, 1.0);
  EXPECT_NEAR(index.at({5e5, 0, 0}), 0.5, 1e-9);     // halfway along the first pass
  EXPECT_TRUE(std::isinf(index.at({5e5, 5e4, 0})));  // between passes
}

}  // namespace
