// The seed's chapter 2 numbers (issue 22, checks 1 and 2): PCA descriptors of both test surfaces at
// 80 x 80, the critical slopes, the analytic plane times, and the cross-shaped counterexample.
#include "paths/finish/move_time.hpp"
#include "paths/cutter/stepover.hpp"
#include "paths/orient/orientation_under_limits.hpp"
#include "paths/finish/pca.hpp"
#include "paths/finish/plane_model.hpp"
#include "paths/finish/surface_samples.hpp"
#include "tests/geometry/test_surfaces.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace {

using namespace drom::paths;
constexpr double kDeg = std::numbers::pi / 180;
const Tool kTorus{ToolKind::torus, 5, 2}, kBall{ToolKind::ball, 5, 5};
const Kinematics kSeed{};  // 5 m/min, 6 m/s^2, 40 m/s^3

PcaPlane surface_plane(const drom::geometry::NurbsSurface& s) { return pca_plane(sample_surface(s, {}, 80, 80).points); }

void expect_within(double value, double reference, double relative, const char* what) {
  EXPECT_LE(std::abs(value - reference), relative * std::abs(reference)) << what << ": " << value << " against the seed's " << reference;
}

TEST(PcaDescriptors, RubioWithinHalfAPercentOfTheSeed) {
  const PcaPlane p = surface_plane(drom::tests::rubio_surface());
  expect_within(p.lambda(0), 572.62, 0.005, "lambda_I");
  expect_within(p.lambda(1), 133.31, 0.005, "lambda_II");
  expect_within(p.shape_factor, 2.07, 0.005, "mu~");
  expect_within(p.size, 3315.47, 0.005, "chi~");
  expect_within(p.slope / kDeg, 42.34, 0.005, "s~ (deg)");
  EXPECT_NEAR(p.steepest_azimuth / kDeg, 66.97, 0.1);  // the steepest direction's azimuth
}

TEST(PcaDescriptors, ChoiWithinHalfAPercentOfTheSeed) {
  const PcaPlane p = surface_plane(drom::tests::choi_surface());
  expect_within(p.lambda(0), 312.07, 0.005, "lambda_I");
  expect_within(p.lambda(1), 219.02, 0.005, "lambda_II");
  expect_within(p.shape_factor, 1.19, 0.005, "mu~");
  expect_within(p.size, 3137, 0.005, "chi~");
  EXPECT_NEAR(std::abs(p.principal_azimuth) / kDeg, 90.0, 0.1);  // the principal direction runs along Y
  expect_within(p.slope / kDeg, 17.13, 0.005, "s~ (deg)");
}

TEST(CriticalSlope, PlaneRubioAndChoiToATenthOfADegree) {
  // With the descriptors as the seed prints them (mu~ 2.07 and 1.19, chi~ 3315.47 and 3137 mm^2).
  EXPECT_NEAR(critical_slope(2, 56 * 28, kTorus, kBall, 0.01, kSeed) / kDeg, 33.8, 0.1);
  EXPECT_NEAR(critical_slope(2.07, 3315.47, kTorus, kBall, 0.01, kSeed) / kDeg, 38.9, 0.1);
  EXPECT_NEAR(critical_slope(1.19, 3137, kTorus, kBall, 0.01, kSeed) / kDeg, 62.6, 0.1);
  // With our unrounded descriptors: Choi's mu~ is 1.1937, and s_c falls 0.2 deg (docs/finishing.md).
  const PcaPlane rubio = surface_plane(drom::tests::rubio_surface()), choi = surface_plane(drom::tests::choi_surface());
  EXPECT_NEAR(critical_slope(rubio.shape_factor, rubio.size, kTorus, kBall, 0.01, kSeed) / kDeg, 38.86, 0.01);
  EXPECT_NEAR(critical_slope(choi.shape_factor, choi.size, kTorus, kBall, 0.01, kSeed) / kDeg, 62.39, 0.01);
  // The verdicts of §2.4.2: the ball on Rubio, the torus on Choi.
  EXPECT_TRUE(choose_tool(rubio, kTorus, kBall, 0.01, kSeed).ball);
  EXPECT_FALSE(choose_tool(choi, kTorus, kBall, 0.01, kSeed).ball);
}

TEST(CriticalShapeFactor, IsTheInverseOfTheCriticalSlope) {
  for (const double mu : {1.5, 2.0, 4.0}) {
    const double s = critical_slope(mu, 2000, kTorus, kBall, 0.01, kSeed);
    EXPECT_NEAR(critical_shape_factor(s, 2000, kTorus, kBall, 0.01, kSeed), mu, 1e-6 * mu);
    // At the critical slope the two analytic times tie.
    const double w = std::sqrt(mu * 2000), h = std::sqrt(2000 / mu);
    EXPECT_NEAR(torus_along_slope(w, h, s, kTorus, 0.01, kSeed).time, ball_along_principal(w, h, kBall, 0.01, kSeed).time, 1e-6 * w);
  }
}

TEST(PlaneTimes, TheSeedsInclinedPlane) {
  const PlaneTime t1 = torus_along_slope(56, 28, 60 * kDeg, kTorus, 0.01, kSeed), t2 = ball_along_principal(56, 28, kBall, 0.01, kSeed);
  EXPECT_NEAR(t1.time, 43.06, 0.005);
  EXPECT_NEAR(t2.time, 37.34, 0.005);
  EXPECT_NEAR(effective_radius(kTorus, 60 * kDeg, 0), 5.46, 0.005);  // Table 2.1
  EXPECT_NEAR(t1.stepover, 0.661, 0.0005);
  EXPECT_NEAR(t2.stepover, 0.632, 0.0005);
}

TEST(PlaneTimes, TheCrossShapedCounterexample) {
  // §4.5.3: a ball R5 on a horizontal cross, p = 40, q = 10, w = 80, h = 30 (T2 with w/V, the digest's fix).
  const double p = 40, q = 10, w = 80, h = 30;
  const auto ball = [&](double along, double across) { return ball_along_principal(along, across, kBall, 0.01, kSeed).time; };
  const double along_x = 2 * ball(q, p) + ball(w, h), along_y = 2 * ball(h, (w - q) / 2) + ball(h + 2 * p, q), zones = 2 * ball(p, q) + ball(w, h);
  EXPECT_NEAR(along_x, 90.4, 0.1);
  EXPECT_NEAR(along_y, 82.3, 0.1);
  EXPECT_NEAR(zones, 74.2, 0.1);
  // Its principal direction is X nonetheless: lambda_1 = 402 > lambda_2 = 395 mm^2.
  EXPECT_NEAR((2 * p * q * q * q + h * w * w * w) / (12 * (w * h + 2 * p * q)), 402, 0.5);
  EXPECT_NEAR(((w - q) * h * h * h + q * std::pow(2 * p + h, 3)) / (12 * (q * (2 * p + h) + (w - q) * h)), 395, 0.9);  // 395.8: the seed rounds down
}

TEST(MoveTime, MachinesDoubleSGivesTheSeedsClosedForms) {
  // The seed's eqs. 1.13-1.15 as the test reference (the search times moves with machine/'s double S).
  const Kinematics k = kSeed;
  const double V = k.feed, J = k.jerk;
  for (const double L : {0.3, 2.0, 7.0, 8.0, 30.0, 80.0}) {
    const double reference = L >= 2 * V * std::sqrt(V / J) ? L / V + 2 * std::sqrt(V / J) : 4 * std::cbrt(L / (2 * J));
    EXPECT_NEAR(rest_to_rest_time(L, k), reference, 1e-9 * (1 + reference)) << L;
  }
  // Where A is reached (a fast machine): case 1, and the regime the seed leaves out.
  const Kinematics fast{1000, 2000, 100000};
  EXPECT_NEAR(rest_to_rest_time(2000, fast), 2000 / 1000.0 + 1000 / 2000.0 + 2000 / 100000.0, 1e-9);
  const double v = 0.5 * (-(2000.0 * 2000 / 100000) + std::sqrt(std::pow(2000.0 * 2000 / 100000, 2) + 4 * 2000 * 300.0));
  EXPECT_NEAR(rest_to_rest_time(300, fast), 2 * (v / 2000 + 2000.0 / 100000), 1e-9);
}

TEST(Tool, EffectiveRadiusAndStepovers) {
  EXPECT_DOUBLE_EQ(effective_radius(kBall, 0.7, 0.3), 5);
  EXPECT_NEAR(effective_radius(kTorus, 30 * kDeg, 90 * kDeg), 2, 1e-12);  // across the slope: the corner radius
  EXPECT_NEAR(flat_scallop(flat_stepover(0.01, 5.46), 5.46), 0.01, 1e-12);
  // The curved step tends to eq. 2.3 on flat ground; convex ground needs less, concave allows more.
  EXPECT_NEAR(curved_stepover(0.01, 5, 1e-9), flat_stepover(0.01, 5), 1e-8);
  EXPECT_LT(curved_stepover(0.01, 5, -1.0 / 20), flat_stepover(0.01, 5));
  EXPECT_GT(curved_stepover(0.01, 5, 1.0 / 20), flat_stepover(0.01, 5));
  EXPECT_EQ(curved_stepover(0.01, 5, 1.0 / 4), 0);  // more concave than the tool: it gouges
  // Against the two-circle geometry computed directly: ground of radius 20, convex.
  const double rho = 20, R = 5, sh = 0.01, w = curved_stepover(sh, R, -1 / rho), phi = w / rho;
  const Eigen::Vector2d c1(0, rho + R), c2(std::sin(phi) * (rho + R), std::cos(phi) * (rho + R));
  // The crest on the bisector at rho + sh is at distance R from both centres.
  EXPECT_NEAR(((rho + sh) * Eigen::Vector2d(std::sin(phi / 2), std::cos(phi / 2)) - c1).norm(), R, 1e-9);
  EXPECT_NEAR(((rho + sh) * Eigen::Vector2d(std::sin(phi / 2), std::cos(phi / 2)) - c2).norm(), R, 1e-9);
}

}  // namespace
