// The laser sheet and position synchronization shared by the closed loop and the blank-deviation
// identification: what a calibration error and a desynchronization do to the readings.
#include "online/dead_reckoning.hpp"
#include "online/laser_sheet.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace drom::online;

namespace {
// A plane z = 8 + a x + b y over [0, 500] x [0, 500]; nothing elsewhere.
HeightField plane(double a, double b) {
  return [=](double x, double y) -> std::optional<double> {
    if (x < 0 || x > 500 || y < 0 || y > 500) return std::nullopt;
    return 8 + a * x + b * y;
  };
}
}  // namespace

TEST(LaserSheet, ReadsTheSurfaceUnderItsPoints) {
  LaserSheet sheet;  // [50, 0, 80] from the tip, across x (90 deg), 80 mm, 800 points
  const auto p = sheet.footprint({100, 200, 8});
  ASSERT_EQ(p.size(), 800u);
  EXPECT_NEAR(p.front().x(), 150, 1e-12);
  EXPECT_NEAR(p.front().y(), 160, 1e-12);
  EXPECT_NEAR(p.back().y(), 240, 1e-12);
  std::mt19937 rng(1);
  const auto pts = scan(sheet, {}, {100, 200, 8}, {100, 200, 8}, plane(0.01, -0.02), rng);
  for (const auto& q : pts) EXPECT_NEAR(q.z, 8 + 0.01 * q.x - 0.02 * q.y, 1e-12);
}

TEST(LaserSheet, OffsetErrorBiasesHeightsBySlopeTimesOffset) {
  // Seed §2.3.2: a sensor offset error shifts where heights are read, so on a slope the surface
  // seems displaced by slope x offset (here 1 mm along x on a 1 % slope: 0.01 mm).
  LaserSheet sheet;
  SensorErrors errors;
  errors.offset_error = {1.0, 0, 0};
  std::mt19937 rng(2);
  const auto pts = scan(sheet, errors, {100, 200, 8}, {100, 200, 8}, plane(0.01, 0), rng);
  for (const auto& q : pts) EXPECT_NEAR(q.z - (8 + 0.01 * q.x), 0.01, 1e-12);
  // An angle error on a slope across the sheet's centre line tilts the profile: the bias grows
  // linearly along the sheet, opposite at its two ends.
  errors = {};
  errors.angle_error_deg = 1.0;
  const auto tilted = scan(sheet, errors, {100, 200, 8}, {100, 200, 8}, plane(0.01, 0), rng);
  const double end_bias = tilted.back().z - (8 + 0.01 * tilted.back().x), start_bias = tilted.front().z - (8 + 0.01 * tilted.front().x);
  EXPECT_NEAR(end_bias, -start_bias, 1e-12);
  EXPECT_NEAR(std::abs(end_bias), 0.01 * 40 * std::sin(M_PI / 180), 1e-9);
}

TEST(LaserSheet, NoReadingWhereThereIsNoPartAndNoiseHasItsSigma) {
  LaserSheet sheet;
  std::mt19937 rng(3);
  const auto off = scan(sheet, {}, {450, 20, 8}, {450, 20, 8}, plane(0, 0), rng);  // centre x = 500, y from -20 to 60
  int missing = 0;
  for (const auto& q : off) missing += std::isnan(q.z) || q.y < 0;
  EXPECT_GT(missing, 150);
  int nan_off_part = 0;
  for (const auto& q : off) nan_off_part += q.y < 0 && std::isnan(q.z);
  int off_part = 0;
  for (const auto& q : off) off_part += q.y < 0;
  EXPECT_EQ(nan_off_part, off_part);
  sheet.range = 50;  // emitter 80 mm above the tip, surface at the tip: out of range
  const auto far = scan(sheet, {}, {100, 200, 8}, {100, 200, 8}, plane(0, 0), rng);
  for (const auto& q : far) EXPECT_TRUE(std::isnan(q.z));
  sheet.range = 200;
  SensorErrors noisy;
  noisy.noise_sd = 0.05;
  double sum = 0, sq = 0;
  for (int k = 0; k < 10; ++k)
    for (const auto& q : scan(sheet, noisy, {100, 200, 8}, {100, 200, 8}, plane(0, 0), rng)) sum += q.z - 8, sq += (q.z - 8) * (q.z - 8);
  const double n = 8000, sd = std::sqrt(sq / n - (sum / n) * (sum / n));
  EXPECT_NEAR(sd, 0.05, 0.05 * 0.05);
}

TEST(DeadReckoning, FollowsTheProgramBetweenEdgesAndResetsAtEach) {
  // Two 100 mm moves at 10 mm/s, synchronized at both ends and in the middle.
  Eigen::MatrixXd path(3, 4);
  path << 0, 0, 8, 0, 100, 0, 8, 10, 100, 100, 8, 20;
  DeadReckoning dr(path, {0, 1, 2});
  // The machine runs 10 % fast (feed override 1.1); its edges arrive 0.2 s late.
  const double override = 1.1, delay = 0.2;
  dr.edge(0, 0 + delay);
  // 5 s after the start the tool is at 55 mm; the estimate says 10 * (5 - 0.2) = 48 mm.
  EXPECT_NEAR(dr.position(5).x(), 48, 1e-12);
  // Never past the next synchronized waypoint: at clock 12 it waits at (100, 0).
  EXPECT_NEAR(dr.position(12).x(), 100, 1e-12);
  EXPECT_NEAR(dr.position(12).y(), 0, 1e-12);
  // The edge of waypoint 1 (reached at 10 / 1.1 s) resets it.
  dr.edge(1, 10 / override + delay);
  const double clock = 15;
  const double truth = 10 * override * clock - 100, estimate = dr.position(clock).y();
  EXPECT_NEAR(estimate, 10 * (clock - 10 / override - delay), 1e-12);
  EXPECT_NEAR(truth - estimate, 10 * ((override - 1) * (clock - 10 / override) + delay), 1e-9);  // the synchronization error
  EXPECT_THROW(dr.edge(5, 20), std::invalid_argument);
  EXPECT_THROW(DeadReckoning(path, {2, 1}), std::invalid_argument);
}
