// The jerk-limited transition against the rest-to-rest closed forms of Herraz 2021 §1.6.2
// (../shared/reference/002-digest.md §2.5) in each of its three regimes, and against the closed form
// of the regime it leaves out (acceleration reached, speed not).
#include "machine/scurve.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace drom::machine;

namespace {

double rest_to_rest(double length, const MotionLimits& m) { return plan_double_s(0, 0, length, m).duration(); }

}  // namespace

TEST(SCurve, RestToRestMatchesTheThreeClosedFormsAndTheMissingRegime) {
  // Regime 1 (t_A < t_V, t_A < t_l): A and V reached. t = 2l/V + A/J + V/A.
  {
    const MotionLimits m{500, 2000, 40000};
    const double L = 200;
    ASSERT_LT(m.acceleration / m.jerk, std::sqrt(m.speed / m.jerk));
    EXPECT_NEAR(rest_to_rest(L, m), L / m.speed + m.acceleration / m.jerk + m.speed / m.acceleration, 1e-9 * (L / m.speed));
  }
  // Regime 2 (t_V < t_A, t_V < t_l): V reached, A not: the thesis's values, a 100 mm pass. t = 2l/V + 2√(V/J).
  {
    const MotionLimits m{5000.0 / 60, 6000, 40000};
    const double L = 100, expected = L / m.speed + 2 * std::sqrt(m.speed / m.jerk);
    EXPECT_NEAR(rest_to_rest(L, m), expected, 1e-9 * expected);
    EXPECT_NEAR(expected, 1.291288, 1e-6);
  }
  // Regime 3 (t_l smallest): neither; the thesis's 4 mm link. t = 4∛(l/J), l = L/2.
  {
    const MotionLimits m{5000.0 / 60, 6000, 40000};
    const double L = 4, expected = 4 * std::cbrt(L / 2 / m.jerk);
    EXPECT_NEAR(rest_to_rest(L, m), expected, 1e-9 * expected);
  }
  // The missing regime: A reached, V not. v_p = (-A²/J + √(A⁴/J² + 8 A l)) / 2, t = 2 (v_p / A + A / J).
  {
    const MotionLimits m{500, 2000, 40000};
    const double L = 60, l = L / 2, A = m.acceleration, J = m.jerk;
    const double vp = (-A * A / J + std::sqrt(A * A * A * A / (J * J) + 8 * A * l)) / 2;
    ASSERT_GT(vp, A * A / J);
    ASSERT_LT(vp, m.speed);
    const double expected = 2 * (vp / A + A / J);
    const DoubleS plan = plan_double_s(0, 0, L, m);
    EXPECT_NEAR(plan.duration(), expected, 1e-9 * expected);
    EXPECT_NEAR(plan.v_peak, vp, 1e-9 * vp);
  }
}

TEST(SCurve, TimeIsContinuousAcrossTheRegimeBoundaries) {
  const MotionLimits m{5000.0 / 60, 6000, 40000};
  // Regimes 2 and 3 meet at l = √(V³/J): the time is 4 t_V on both sides.
  const double l = std::sqrt(m.speed * m.speed * m.speed / m.jerk);
  EXPECT_NEAR(rest_to_rest(2 * l * (1 - 1e-9), m), rest_to_rest(2 * l * (1 + 1e-9), m), 1e-7);
  EXPECT_NEAR(rest_to_rest(2 * l, m), 4 * std::sqrt(m.speed / m.jerk), 1e-9);
}

TEST(SCurve, ProfilesIntegrateToTheirLengthAndEndSpeeds) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (int trial = 0; trial < 2000; ++trial) {
    const MotionLimits m{10 + 500 * u(rng), 100 + 5000 * u(rng), 1000 + 100000 * u(rng)};
    double v0 = m.speed * u(rng), v1 = m.speed * u(rng);
    const double needed = speed_change_distance(v0, v1, m.acceleration, m.jerk);
    const double length = needed + 50 * u(rng) * u(rng);
    const DoubleS plan = plan_double_s(v0, v1, length, m);
    const DoubleS::State end = plan.at(plan.duration());
    // Integrate the phases independently (the piecewise cubic sampled finely) and compare.
    const int steps = 4000;
    double s = 0, vmax = 0, amax = 0;
    for (int k = 0; k < steps; ++k) {
      const double t0 = plan.duration() * k / steps, t1 = plan.duration() * (k + 1) / steps;
      const auto a = plan.at(t0), b = plan.at(t1), c = plan.at(0.5 * (t0 + t1));
      s += (t1 - t0) * (a.v + 4 * c.v + b.v) / 6;  // Simpson: exact for the cubic s(t) up to the phase breaks
      vmax = std::max(vmax, c.v);
      amax = std::max(amax, std::abs(c.a));
    }
    EXPECT_NEAR(end.s, length, 1e-9 * std::max(1.0, length));
    EXPECT_NEAR(end.v, v1, 1e-9 * m.speed);
    EXPECT_NEAR(s, length, 1e-6 * std::max(1.0, length));
    EXPECT_LE(vmax, m.speed * (1 + 1e-9));
    EXPECT_LE(amax, m.acceleration * (1 + 1e-9));
    // time_at inverts at.
    const double t = plan.duration() * u(rng);
    EXPECT_NEAR(plan.time_at(plan.at(t).s), t, 1e-9 * std::max(1.0, plan.duration()));
  }
}

TEST(SCurve, ReachableSpeedCoversExactlyTheDistance) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  for (int trial = 0; trial < 5000; ++trial) {
    const double A = 100 + 5000 * u(rng), J = 1000 + 100000 * u(rng), v0 = 200 * u(rng), d = 0.001 + 100 * u(rng) * u(rng);
    const double v = reachable_speed(v0, d, 1e9, A, J);
    EXPECT_NEAR(speed_change_distance(v0, v, A, J), d, 1e-9 * std::max(1.0, d));
    EXPECT_LE(reachable_speed(v0, d, 0.5 * v + 0.5 * v0, A, J), 0.5 * v + 0.5 * v0);
  }
}

TEST(SCurve, IncompatibleEndSpeedsAreRefused) {
  EXPECT_THROW(plan_double_s(0, 100, 1e-3, {200, 1000, 10000}), std::invalid_argument);
  EXPECT_THROW(plan_double_s(0, 0, 1, {0, 1000, 10000}), std::invalid_argument);
}
