// geometry/cloud_noise_floor: a floor over a noisy scan that the true surface does not rise through.
// A ball resting on noisy points stands under the true surface wherever the few under it read low
// (issue 45: 0.017 mm on a cap under 0.027 mm of noise, the tolerance 0.01). The floor's upper points
// must stand above the true surface (but, rarely, by a few microns where one fit of thousands is off
// by more than its lift), and not by much more than the noise (the stock the finishing leaves).
#include "geometry/cloud_noise_floor.hpp"

#include "geometry/cloud_kdtree.hpp"
#include "geometry/cloud_noise.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <vector>

namespace {

struct Surface {
  const char* name;
  double (*height)(double, double);
};

// Points at random over [-12, 12]^2 (where the surface is), noise along z.
std::vector<Eigen::Vector3d> scan(const Surface& s, double spacing, double noise, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-12, 12);
  std::normal_distribution<double> n(0, noise > 0 ? noise : 1);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < static_cast<int>(24 * 24 / (spacing * spacing)); ++i) {
    const double x = u(rng), y = u(rng), z = s.height(x, y);
    if (!std::isfinite(z)) continue;  // beyond the ball's silhouette
    points.emplace_back(x, y, z + (noise > 0 ? n(rng) : 0.0));
  }
  return points;
}

}  // namespace

TEST(CloudNoiseFloor, StandsAboveTheTrueSurfaceByAboutTheNoise) {
  const Surface surfaces[] = {{"cap", [](double x, double y) { return 10 - (x * x + y * y) / 40; }},
                              {"saddle", [](double x, double y) { return 10 + (x * x - 0.7 * y * y) / 30; }},
                              {"ball R 16", [](double x, double y) { return std::sqrt(16 * 16 - x * x - y * y); }}};
  unsigned seed = 21;
  for (const Surface& s : surfaces)
    for (const double noise : {0.01, 0.03, 0.08}) {
      const auto points = scan(s, 0.2, noise, seed++);
      const drom::geometry::ScanSurvey survey(points);
      const double measured = drom::geometry::scan_noise(points, survey.tree);
      const auto floor = drom::geometry::noise_floor(points, survey, measured);
      // The upper point of each pair, against the true surface over its (x, y), away from the edges.
      std::vector<double> above;
      for (std::size_t k = 0; k + 1 < floor.points.size(); k += 2) {
        const Eigen::Vector3d& a = floor.points[k];
        const Eigen::Vector3d& b = floor.points[k + 1];
        const Eigen::Vector3d& upper = a.z() > b.z() ? a : b;
        if (std::abs(upper.x()) > 10 || std::abs(upper.y()) > 10) continue;
        above.push_back(upper.z() - s.height(upper.x(), upper.y()));
      }
      ASSERT_GT(above.size(), points.size() / 2) << s.name << ": most points have a smooth neighbourhood";
      std::sort(above.begin(), above.end());
      const double lowest = above.front(), median = above[above.size() / 2];
      std::printf("  %-9s noise %.3f (measured %.4f): %zu fits, lift %.2f deviations; upper points from %+.4f to %+.4f mm, median %+.4f\n", s.name, noise, measured,
                  floor.fits, floor.deviations, lowest, above.back(), median);
      // The lift keeps the lowest of all the fits above the surface with odds of about 10 to 1: over
      // nine scans one fit may dip, and a ball rests on the highest under it. None by half the
      // finishing's tolerance, and hardly any at all.
      const auto under = static_cast<double>(std::count_if(above.begin(), above.end(), [](double a) { return a < -0.001; }));
      EXPECT_GT(lowest, -0.005) << s.name << " under " << noise << " mm of noise: the floor dips under the surface";
      EXPECT_LT(under / static_cast<double>(above.size()), 1e-3) << s.name << " under " << noise << " mm of noise";
      EXPECT_LT(median, 2.5 * noise) << s.name << ": the floor stands too high (stock)";
    }
}

TEST(CloudNoiseFloor, ACleanScanHasNone) {
  const Surface cap{"cap", [](double x, double y) { return 10 - (x * x + y * y) / 40; }};
  const auto points = scan(cap, 0.3, 0.0, 5);
  const drom::geometry::ScanSurvey survey(points);
  const auto floor = drom::geometry::noise_floor(points, survey, drom::geometry::scan_noise(points, survey.tree));
  EXPECT_TRUE(floor.points.empty());
}

// Beside a sharp crest the 40 nearest points straddle it and no quadric fits them: the floor stands on
// the point's own flank's plane there. Without it a ridge's flank 0.3 mm from its crest had no floor,
// and a ball resting on the crest's line and on the flank's low points went 0.013 mm into the flank
// (issue 45's seed 4242, ridge 1: flanks at 40°, a 0.21 mm grid, σ 0.007).
TEST(CloudNoiseFloor, StandsOnEachFlankBesideASharpCrest) {
  struct Ridge {
    double degrees, spacing, noise;
  };
  unsigned seed = 71;
  // Where 40 points can tell the crest from a quadric: under more noise (30° under σ 0.03) a quadric
  // fits them, rounds the crest off below the truth, and the crease's own line (geometry/cloud_creases)
  // is what holds the tool there.
  for (const Ridge r : {Ridge{40, 0.21, 0.007}, Ridge{47, 0.25, 0.017}, Ridge{35, 0.3, 0.01}}) {
    const double m = std::tan(r.degrees * 3.14159265358979 / 180);
    const auto height = [m](double x) { return 20 - m * std::abs(x); };
    std::mt19937 rng(seed++);
    std::uniform_real_distribution<double> u(-8, 8);
    std::normal_distribution<double> n(0, r.noise);
    std::vector<Eigen::Vector3d> points;
    for (int i = 0; i < static_cast<int>(16 * 16 / (r.spacing * r.spacing)); ++i) {
      const double x = u(rng), y = u(rng);
      points.emplace_back(x, y, height(x) + n(rng));
    }
    const drom::geometry::ScanSurvey survey(points);
    const double measured = drom::geometry::scan_noise(points, survey.tree);
    const auto floor = drom::geometry::noise_floor(points, survey, measured);
    // Scan points within 0.5 mm of the crest (and 1 mm clear of the scan's edges) that got a floor.
    std::vector<char> floored(points.size(), 0);
    for (const int s : floor.source) floored[static_cast<std::size_t>(s)] = 1;
    std::size_t near_crest = 0, near_crest_floored = 0;
    for (std::size_t i = 0; i < points.size(); ++i) {
      if (std::abs(points[i].x()) > 0.5 || std::abs(points[i].y()) > 7) continue;
      ++near_crest, near_crest_floored += floored[i];
    }
    std::vector<double> above;
    for (std::size_t k = 0; k + 1 < floor.points.size(); k += 2) {
      const Eigen::Vector3d& a = floor.points[k];
      const Eigen::Vector3d& b = floor.points[k + 1];
      const Eigen::Vector3d& upper = a.z() > b.z() ? a : b;
      if (std::abs(upper.x()) > 7 || std::abs(upper.y()) > 7) continue;
      // Against the flank under it: the nearest of the two planes, along z.
      above.push_back(upper.z() - height(upper.x()));
    }
    ASSERT_FALSE(above.empty());
    std::sort(above.begin(), above.end());
    const double share = static_cast<double>(near_crest_floored) / static_cast<double>(std::max<std::size_t>(near_crest, 1));
    std::printf("  ridge %.0f deg, spacing %.2f, noise %.3f (measured %.4f): %.0f %% of the points within 0.5 mm of the crest floored; upper points from %+.4f mm, median %+.4f\n",
                r.degrees, r.spacing, r.noise, measured, 100 * share, above.front(), above[above.size() / 2]);
    EXPECT_GT(share, 0.5) << r.degrees << "°: the points beside the crest have no floor";
    EXPECT_GT(above.front(), -0.005) << r.degrees << "°: the floor dips under a flank";
    EXPECT_LT(above[above.size() / 2], 2.5 * r.noise) << r.degrees << "°: the floor stands too high (stock)";
  }
}
