// geometry/cloud_holes: the points put where a scan has none. A ball resting on them must stay above
// the true surface, so every filled spot's upper point must stand above it, however many spots a
// sparse noisy scan fills; and not so far above that the finishing leaves a thick skin. The lift is
// the normal quantile at 1 - 1 / (10 fits), checked against the table's values.
#include "geometry/cloud_cells.hpp"
#include "geometry/cloud_holes.hpp"
#include "geometry/cloud_noise.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <vector>

namespace {

// A saddle like the shape family's saddle 4 (tests/paths/copy/shape_family.hpp), seen from above.
double saddle(double x, double y) { return 12.3 + x * x / (2 * 181.0) - y * y / (2 * 160.0); }

std::vector<Eigen::Vector3d> sparse_noisy_saddle(int count, double noise, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> x(-14, 14), y(-29, 29);
  std::normal_distribution<double> n(0, noise);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < count; ++i) {
    const double px = x(rng), py = y(rng);
    points.emplace_back(px, py, saddle(px, py) + n(rng));
  }
  return points;
}

}  // namespace

TEST(SafeLift, IsTheNormalQuantileOfOneInTenTimesTheFits) {
  using drom::geometry::safe_lift_deviations;
  EXPECT_DOUBLE_EQ(safe_lift_deviations(0), 3.0);
  EXPECT_DOUBLE_EQ(safe_lift_deviations(1), 3.0);   // 1.28 by the quantile: never under 3
  EXPECT_NEAR(safe_lift_deviations(100), 3.0902, 2e-4);    // tail 1e-3
  EXPECT_NEAR(safe_lift_deviations(2000), 3.8906, 2e-4);   // tail 5e-5
  EXPECT_NEAR(safe_lift_deviations(100000), 4.7534, 2e-4);  // tail 1e-6
}

// 2 000 points at random over 28 x 58 mm (1.3 mm apart), noise 0.093 mm: the scan of the bench's
// saddle 4, where three deviations of lift left a fill 0.007 mm under the surface and the ball 0.048 mm
// into it. Every filled spot's upper point stands above the saddle; the median no more than 0.15 mm.
TEST(CloudHoles, ASparseNoisyScanIsFilledAboveItsSurfaceEverywhere) {
  constexpr double kNoise = 0.093, kHole = 0.1225;  // the hole radius drom copy uses for a ball D6 at Tu 0.01
  for (const unsigned seed : {9191u, 4545u}) {
    const auto points = sparse_noisy_saddle(2000, kNoise, seed);
    const double noise = drom::geometry::scan_noise(points);
    ASSERT_GT(noise, 0.7 * kNoise);
    ASSERT_LT(noise, 1.3 * kNoise);
    const auto filled = drom::geometry::fill_holes(points, kHole, noise);
    ASSERT_TRUE(filled.needed);
    ASSERT_EQ(filled.points.size(), filled.source.size());
    // The points come in pairs from one spot, lifted above and below it: the upper one is the ball's.
    std::vector<double> above;
    double lowest = 1e9;
    for (std::size_t k = 0; k + 1 < filled.points.size(); k += 2) {
      ASSERT_EQ(filled.source[k], filled.source[k + 1]);
      const Eigen::Vector3d& a = filled.points[k];
      const Eigen::Vector3d& b = filled.points[k + 1];
      const Eigen::Vector3d& upper = a.z() > b.z() ? a : b;
      const double d = upper.z() - saddle(upper.x(), upper.y());
      above.push_back(d);
      lowest = std::min(lowest, d);
    }
    ASSERT_GT(above.size(), 20000u) << "a scan this sparse is filled nearly everywhere";
    std::nth_element(above.begin(), above.begin() + static_cast<long>(above.size() / 2), above.end());
    const double median = above[above.size() / 2];
    std::printf("seed %u: noise %.4f mm, %zu spots filled, lowest upper point %.4f mm above the saddle, median %.4f mm\n", seed, noise, above.size(),
                lowest, median);
    EXPECT_GT(lowest, 0.0) << "a filled spot lies below the true surface: the ball would cut into it there";
    EXPECT_LT(median, 0.15);
  }
}

TEST(CloudHoles, ADenseScanNeedsNone) {
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 120; ++i)
    for (int j = 0; j < 120; ++j) points.emplace_back(i * 0.05, j * 0.05, saddle(i * 0.05, j * 0.05));
  const auto filled = drom::geometry::fill_holes(points, 0.1225, 0.0);
  EXPECT_FALSE(filled.needed);
  EXPECT_TRUE(filled.points.empty());
}

// A noise-free scan of a step, 0.8 mm apart at random on the plateaus and in rows on the wall (the
// shape family's step 1 of seed 5150): a point of the upper plateau near the wall's top whose 16
// nearest held one row of the wall and a plateau point beside it fitted them as an exact chamfer
// under the corner, filled the gap there 0.17 to 0.30 mm low, and the ball went 0.011 mm into the
// plateau (0.037 mm on another draw, where the 16 nearest of the wall's top row make no model at all).
// A ball of radius 3 lowered onto the scan and its fill over the upper plateau's first 4 mm from the
// wall sinks no deeper than over its middle, where the fill's spacing alone sets how deep (6 draws).
TEST(CloudHoles, ABallOnAStepsFilledScanDoesNotSinkBesideTheWallsTop) {
  constexpr double a = 14, b = 23, xw = -4.8, rise = 3.4, gx = -0.05, gy = -0.22, spacing = 0.79, radius = 3;
  const auto f = [&](double x, double y) { return 8 + (x >= xw ? rise : 0.0) + gx * (x - xw) + gy * y; };
  for (const unsigned seed : {5150u, 11u, 12u, 13u, 14u, 15u}) {
    std::mt19937 rng(seed);
    std::uniform_real_distribution<double> ux(-a, a), uy(-b, b), u01(0, 1);
    std::vector<Eigen::Vector3d> points;
    for (int i = 0; i < static_cast<int>(4 * a * b / (spacing * spacing)); ++i) {
      const double x = ux(rng), y = uy(rng);
      points.emplace_back(x, y, f(x, y));
    }
    // The wall in rows at fixed fractions of its height, as a scanner's lines cross it.
    const int rows = static_cast<int>(std::ceil(rise / spacing)), along = static_cast<int>(std::ceil(2 * b / spacing));
    for (int k = 0; k <= along; ++k)
      for (int l = 1; l < rows; ++l) {
        const double y = -b + 2 * b * u01(rng);
        points.emplace_back(xw, y, f(xw - 1e-9, y) + rise * l / rows);
      }
    const auto filled = drom::geometry::fill_holes(points, 0.1225, 0.0);
    ASSERT_TRUE(filled.needed);
    std::vector<Eigen::Vector3d> all = points;
    all.insert(all.end(), filled.points.begin(), filled.points.end());
    // In 1 mm columns, for the ball's drop.
    std::map<std::pair<int, int>, std::vector<Eigen::Vector3d>> columns;
    for (const auto& p : all) columns[{static_cast<int>(std::floor(p.x())), static_cast<int>(std::floor(p.y()))}].push_back(p);
    // On the plane z = c + gx x + gy y the ball's centre stands R sqrt(1 + gx^2 + gy^2) above it, its
    // contact 0.15 mm towards the wall from the centre: on the plateau from 0.2 mm off the wall.
    const double rest_above_plane = radius * std::sqrt(1 + gx * gx + gy * gy);
    const auto deepest_sink = [&](double from_wall, double to_wall) {
      double deepest = -1;
      for (double x = xw + from_wall; x <= xw + to_wall; x += 0.05)
        for (double y = -b + radius + 0.5; y <= b - radius - 0.5; y += 0.05) {
          double rest = -1e9;
          for (int cx = static_cast<int>(std::floor(x - radius)); cx <= static_cast<int>(std::floor(x + radius)); ++cx)
            for (int cy = static_cast<int>(std::floor(y - radius)); cy <= static_cast<int>(std::floor(y + radius)); ++cy) {
              const auto column = columns.find({cx, cy});
              if (column == columns.end()) continue;
              for (const auto& p : column->second) {
                const double d2 = (p.x() - x) * (p.x() - x) + (p.y() - y) * (p.y() - y);
                if (d2 < radius * radius) rest = std::max(rest, p.z() + std::sqrt(radius * radius - d2));
              }
            }
          deepest = std::max(deepest, f(x, y) + rest_above_plane - rest);
        }
      return deepest;
    };
    // Beside the wall's top, against the plateau's open middle, where the fill's spacing alone sets it.
    const double beside = deepest_sink(0.2, 4), middle = deepest_sink(6, 10);
    std::printf("seed %u: %zu fill points; the ball sinks at most %.4f mm into the plateau beside the wall's top, %.4f mm in its middle\n", seed,
                filled.points.size(), beside, middle);
    EXPECT_LT(beside, middle + 0.001) << "seed " << seed;
    EXPECT_LT(middle, 0.0075) << "seed " << seed;
  }
}
