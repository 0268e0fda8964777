// Check 1 of the point-cloud issue: the ball, flat and torus tools dropped on dense noise-free samples
// of a plane, a sphere and a cylinder stand at the analytic offset height, within the sampling bound;
// the bin grid and the k-d tree give exactly what brute force over every point gives.
#include "geometry/cloud_bins.hpp"
#include "geometry/cloud_kdtree.hpp"
#include "paths/copy/tool_drop.hpp"
#include "tests/paths/copy/test_clouds.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <functional>
#include <random>

namespace {

using namespace drom::paths;
using drom::tests::graph_samples;

const Tool kBall{ToolKind::ball, 3, 3}, kFlat{ToolKind::torus, 3, 0}, kTorus{ToolKind::torus, 4, 1.5};

// A surface z = f(x, y) and the analytic tip height of each tool over node (x, y).
struct Shape {
  const char* name;
  std::function<double(double, double)> f;
  std::function<Eigen::Vector2d(double, double)> gradient;
  std::function<double(const Tool&, double, double)> tip;
  double x0, x1, y0, y1;      // sampled region
  double nodes_margin;        // nodes this far inside it
};

// Tip height of a torus-family tool (R0 = R - r; a ball is r = R, a flat end mill r = 0).
double flat_part(const Tool& t) { return t.kind == ToolKind::ball ? 0.0 : t.radius - t.corner_radius; }
double tube(const Tool& t) { return t.kind == ToolKind::ball ? t.radius : t.corner_radius; }

std::vector<Shape> shapes() {
  const double gx = 0.35, gy = -0.2, K = 20, Kc = 15;
  return {
      {"tilted plane", [=](double x, double y) { return gx * x + gy * y + 1; }, [=](double, double) { return Eigen::Vector2d(gx, gy); },
       [=](const Tool& t, double x, double y) {
         const double g = std::hypot(gx, gy);
         return gx * x + gy * y + 1 + tube(t) * (std::sqrt(1 + g * g) - 1) + flat_part(t) * g;
       },
       -12, 12, -12, 12, 4.5},
      {"sphere", [=](double x, double y) { return std::sqrt(std::max(0.0, K * K - x * x - y * y)); },
       [=](double x, double y) {
         const double z = std::sqrt(std::max(1e-12, K * K - x * x - y * y));
         return Eigen::Vector2d(-x / z, -y / z);
       },
       [=](const Tool& t, double x, double y) {
         const double d = std::hypot(x, y), r = tube(t), a = flat_part(t);
         const double torus = -r + std::sqrt((K + r) * (K + r) - (d - a) * (d - a));
         return d <= a ? std::max(K, torus) : torus;
       },
       -K, K, -K, K, 0},
      {"cylinder", [=](double x, double) { return std::sqrt(std::max(0.0, Kc * Kc - x * x)); },
       [=](double x, double) { return Eigen::Vector2d(-x / std::sqrt(std::max(1e-12, Kc * Kc - x * x)), 0); },
       [=](const Tool& t, double x, double) {
         const double d = std::max(0.0, std::abs(x) - flat_part(t)), r = tube(t);
         return -r + std::sqrt((Kc + r) * (Kc + r) - d * d);
       },
       -Kc, Kc, -12, 12, 4.5},
  };
}

// The most the drop on samples can lose against the continuous surface: the value p_z - h(rho) at
// the analytic contact less its least over the sample spacing's reach of it (the covering radius c
// of the grid; 2c where the contact lies on the tool's rim, so that a whole grid cell fits inside).
// On a plane under a ball it is the digest's R - sqrt(R^2 - c^2).
double sampling_bound(const Shape& s, const Tool& t, double x, double y, double c) {
  const auto value = [&](double qx, double qy) {
    const double rho = std::hypot(qx - x, qy - y);
    return rho > t.radius ? -1e300 : s.f(qx, qy) - bottom_height(t, rho);
  };
  // The contact, by a dense polar search and a local refinement.
  double best = -1e300, bx = x, by = y;
  for (int i = 0; i <= 100; ++i)
    for (int k = 0; k < 120; ++k) {
      const double rho = t.radius * i / 100, a = 2 * std::numbers::pi * k / 120;
      const double v = value(x + rho * std::cos(a), y + rho * std::sin(a));
      if (v > best) best = v, bx = x + rho * std::cos(a), by = y + rho * std::sin(a);
    }
  for (double box = t.radius / 20; box > 1e-7; box /= 4) {
    const double cx = bx, cy = by;
    for (int i = -10; i <= 10; ++i)
      for (int k = -10; k <= 10; ++k) {
        const double v = value(cx + box * i / 10, cy + box * k / 10);
        if (v > best) best = v, bx = cx + box * i / 10, by = cy + box * k / 10;
      }
  }
  const bool rim = std::hypot(bx - x, by - y) > t.radius - 2 * c;
  const double reach = rim ? 2 * c : c;
  double least = best;
  for (int i = 0; i <= 40; ++i)
    for (int k = 0; k < 72; ++k) {
      const double rho = reach * i / 40, a = 2 * std::numbers::pi * k / 72;
      const double v = value(bx + rho * std::cos(a), by + rho * std::sin(a));
      if (v > -1e299) least = std::min(least, v);
    }
  return best - least + 1e-12;
}

TEST(ToolDrop, StandsAtTheAnalyticOffsetWithinTheSamplingBound) {
  const double spacing = 0.1, cover = spacing / std::sqrt(2.0);
  for (const Shape& s : shapes()) {
    const auto cloud = graph_samples(s.f, s.gradient, s.x0, s.x1, s.y0, s.y1, spacing);
    const drom::geometry::CloudBins bins(cloud.points, 1.0);
    std::mt19937 rng(11);
    for (const Tool& t : {kBall, kFlat, kTorus}) {
      double worst = 0, worst_bound = 0;
      for (int k = 0; k < 40; ++k) {
        const double m = s.nodes_margin + t.radius;
        std::uniform_real_distribution<double> ux(s.x0 + m, s.x1 - m), uy(s.y0 + std::max(m, 4.5), s.y1 - std::max(m, 4.5));
        double x = ux(rng), y = uy(rng);
        if (std::string(s.name) == "sphere") {  // nodes whose contact stays on the sampled cap (slope below 60 degrees)
          std::uniform_real_distribution<double> r(0, 10), a(0, 2 * std::numbers::pi);
          const double rr = r(rng), aa = a(rng);
          x = rr * std::cos(aa), y = rr * std::sin(aa);
        }
        const Drop d = drop_tool(bins, x, y, t);
        ASSERT_TRUE(d.contact);
        const double exact = s.tip(t, x, y), bound = sampling_bound(s, t, x, y, cover);
        EXPECT_GE(exact - d.tip, -1e-9) << s.name << " " << t.name() << " at " << x << ", " << y;  // never above the true height
        EXPECT_LE(exact - d.tip, bound) << s.name << " " << t.name() << " at " << x << ", " << y;
        worst = std::max(worst, exact - d.tip), worst_bound = std::max(worst_bound, bound);
      }
      std::printf("%-13s %-14s below the analytic height by at most %.2e mm (bound at most %.2e mm)\n", s.name, t.name().c_str(), worst, worst_bound);
    }
  }
}

TEST(ToolDrop, DigestsBoundOnAPlaneUnderABall) {
  // A level plane sampled on a grid: the ball sinks by R - sqrt(R^2 - c^2) at a node a cell's
  // half-diagonal from every sample, and not at all on a sample.
  const double spacing = 0.5, R = kBall.radius;
  const auto cloud = graph_samples([](double, double) { return 0.0; }, [](double, double) { return Eigen::Vector2d::Zero(); }, -10, 10, -10, 10, spacing);
  const drom::geometry::CloudBins bins(cloud.points, 1.0);
  const double c = spacing / std::sqrt(2.0);
  EXPECT_NEAR(drop_tool(bins, 0.25, 0.25, kBall).tip, -(R - std::sqrt(R * R - c * c)), 1e-12);
  EXPECT_NEAR(drop_tool(bins, 0.5, 0.5, kBall).tip, 0, 1e-12);
  EXPECT_EQ(drop_tool(bins, 0.25, 0.25, kFlat).tip, 0);
}

TEST(ToolDrop, IndexesAgreeExactlyWithBruteForce) {
  // Noisy, uneven samples (with duplicates and points above one another), nodes inside, near the edge
  // and outside (gaps).
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> u(-20, 20), n(-0.3, 0.3);
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 30000; ++i) {
    const double x = u(rng), y = 0.5 * u(rng);
    points.emplace_back(x, y, 0.02 * x * x - 0.1 * y + n(rng));
    if (i % 500 == 0) points.push_back(points.back());                              // a duplicate
    if (i % 700 == 0) points.push_back(points.back() + Eigen::Vector3d(0, 0, 3));   // an overhang above
  }
  const drom::geometry::CloudBins fine(points, 0.4), coarse(points, 3.0);
  const drom::geometry::CloudKdTree tree(points, 2);
  std::vector<int> scratch;
  std::uniform_real_distribution<double> node(-26, 26);
  int gaps = 0;
  for (const Tool& t : {kBall, kFlat, kTorus})
    for (int k = 0; k < 2000; ++k) {
      const double x = node(rng), y = node(rng);
      const Drop brute = drop_brute_force(points, x, y, t);
      for (const Drop& d : {drop_tool(fine, x, y, t), drop_tool(coarse, x, y, t), drop_tool(tree, points, x, y, t, scratch)}) {
        ASSERT_EQ(d.contact, brute.contact);
        if (!brute.contact) continue;
        ASSERT_EQ(d.tip, brute.tip) << t.name() << " at " << x << ", " << y;
        ASSERT_EQ(d.point, brute.point);
        ASSERT_EQ(d.normal, brute.normal);
      }
      gaps += !brute.contact;
    }
  EXPECT_GT(gaps, 100);  // the outside nodes are gaps: no height invented for them
}

TEST(ToolDrop, ContactNormalsAreTheSurfaceNormals) {
  // On the sphere the ball's contact normal is the sphere's normal at the contact to within the
  // sampling's angle; the flat bottom reports the axis.
  const double K = 20;
  const auto cloud = graph_samples([=](double x, double y) { return std::sqrt(std::max(0.0, K * K - x * x - y * y)); },
                                   [=](double x, double y) {
                                     const double z = std::sqrt(std::max(1e-12, K * K - x * x - y * y));
                                     return Eigen::Vector2d(-x / z, -y / z);
                                   },
                                   -K, K, -K, K, 0.05);
  const drom::geometry::CloudBins bins(cloud.points, 1.0);
  for (const auto& [x, y] : {std::pair{3.0, 4.0}, std::pair{-8.0, 2.0}, std::pair{0.0, -11.0}}) {
    const Drop d = drop_tool(bins, x, y, kBall);
    const Eigen::Vector3d contact = cloud.points[static_cast<std::size_t>(d.point)];
    EXPECT_LT(std::acos(std::min(1.0, d.normal.dot(contact.normalized()))), 0.01);
  }
  EXPECT_EQ(drop_tool(bins, 0.3, 0.2, kTorus).normal, Eigen::Vector3d::UnitZ());
}

TEST(ToolDrop, TheHolderLiftsTheToolOverATallNeighbour) {
  // A level floor and a 30 mm post 15 mm away: the cutter alone would sit on the floor; a holder of
  // radius 20 at 25 mm above the tip must clear the post's top.
  std::vector<Eigen::Vector3d> points;
  for (int i = -40; i <= 40; ++i)
    for (int j = -40; j <= 40; ++j) points.emplace_back(0.5 * i, 0.5 * j, 0);
  points.emplace_back(15, 0, 30);
  const drom::geometry::CloudBins bins(points, 1.0);
  ToolAssembly tool{kBall, 0, 0, 25, RevolvedProfile::endless_cylinder(20)};
  const Drop d = drop_assembly(bins, 0, 0, tool);
  EXPECT_TRUE(d.lifted);
  EXPECT_DOUBLE_EQ(d.tip, 30 - 25);
  tool.holder = RevolvedProfile::endless_cylinder(10);  // the post is out of the holder's reach
  EXPECT_FALSE(drop_assembly(bins, 0, 0, tool).lifted);
}

}  // namespace
