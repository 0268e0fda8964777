#include "machine/scurve.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace drom::machine {

double speed_change_time(double delta, double acceleration, double jerk) {
  if (!(delta > 0)) return 0;
  if (delta * jerk >= acceleration * acceleration) return delta / acceleration + acceleration / jerk;
  return 2 * std::sqrt(delta / jerk);
}

double speed_change_distance(double v0, double v1, double acceleration, double jerk) {
  // The speed profile of a transition is point-symmetric about its middle, so its mean speed is (v0 + v1) / 2.
  return 0.5 * (v0 + v1) * speed_change_time(std::abs(v1 - v0), acceleration, jerk);
}

namespace {

// The speed rise x ≥ 0 from v0 covering exactly `distance`, acceleration limit not reached:
// (2 v0 + x) √(x / J) = d, i.e. y³ + 2 v0 y − d √J = 0 with y = √x (one real root, as 2 v0 ≥ 0).
double rise_without_acceleration_limit(double v0, double distance, double jerk) {
  const double p = 2 * v0, q = -distance * std::sqrt(jerk);
  const double root = std::sqrt(q * q / 4 + p * p * p / 27);
  double y = std::cbrt(-q / 2 + root);
  y = y > 0 ? y - p / (3 * y) : 0;  // Cardano, written to avoid the cancellation of cbrt(-q/2 - root)
  for (int i = 0; i < 3 && y > 0; ++i) y -= (y * y * y + p * y + q) / (3 * y * y + p);  // polish to the last bit
  return y * y;
}

// The same with the acceleration limit reached: (2 v0 + x) / 2 · (x / A + A / J) = d, a quadratic in x.
double rise_with_acceleration_limit(double v0, double distance, double acceleration, double jerk) {
  const double b = 2 * v0 + acceleration * acceleration / jerk;
  const double c = 2 * acceleration * (v0 * acceleration / jerk - distance);  // < 0 in this regime
  return -2 * c / (b + std::sqrt(b * b - 4 * c));
}

}  // namespace

double reachable_speed(double v0, double distance, double cap, double acceleration, double jerk) {
  if (v0 >= cap) return cap;
  if (!(distance > 0)) return v0;
  if (speed_change_distance(v0, cap, acceleration, jerk) <= distance) return cap;
  const double x_limit = acceleration * acceleration / jerk;  // the rise at which A is just reached
  const double x = speed_change_distance(v0, v0 + x_limit, acceleration, jerk) >= distance
                       ? rise_without_acceleration_limit(v0, distance, jerk)
                       : rise_with_acceleration_limit(v0, distance, acceleration, jerk);
  return std::min(cap, v0 + x);
}

double DoubleS::duration() const {
  double t = 0;
  for (const Phase& p : phases) t += p.duration;
  return t;
}

DoubleS::State DoubleS::at(double t) const {
  State st{0, v_start, 0, 0};
  for (const Phase& p : phases) {
    const double tau = std::min(std::max(t, 0.0), p.duration);
    const double s = st.s + st.v * tau + st.a * tau * tau / 2 + p.jerk * tau * tau * tau / 6;
    const double v = st.v + st.a * tau + p.jerk * tau * tau / 2;
    const double a = st.a + p.jerk * tau;
    if (t <= p.duration) return {s, v, a, p.jerk};
    st = {s, v, a, p.jerk};
    t -= p.duration;
  }
  return {length, v_end, 0, 0};
}

double DoubleS::time_at(double s) const {
  if (s <= 0) return 0;
  if (s >= length) return duration();
  State st{0, v_start, 0, 0};
  double t0 = 0;
  for (const Phase& p : phases) {
    const double d = p.duration;
    const double s_end = st.s + st.v * d + st.a * d * d / 2 + p.jerk * d * d * d / 6;
    if (s <= s_end) {
      // s(τ) is increasing on the phase (v ≥ 0): Newton's steps on the cubic, kept inside a bracket
      // that bisection shrinks whenever a step would leave it or the speed vanishes; exact to
      // rounding in a few steps where bisection alone took fifty (it was most of drom copy's
      // program time).
      double lo = 0, hi = d, m = d * std::clamp((s - st.s) / std::max(s_end - st.s, 1e-300), 0.0, 1.0);
      for (int i = 0; i < 200 && hi - lo > 1e-15 * (t0 + d); ++i) {
        const double sm = st.s + st.v * m + st.a * m * m / 2 + p.jerk * m * m * m / 6;
        if (sm == s) return t0 + m;
        (sm < s ? lo : hi) = m;
        const double vm = st.v + st.a * m + p.jerk * m * m / 2;
        const double next = vm > 0 ? m - (sm - s) / vm : 0.5 * (lo + hi);
        const double step = std::abs(next - m);
        m = next > lo && next < hi ? next : 0.5 * (lo + hi);
        if (step <= 1e-15 * (t0 + d)) break;
      }
      return t0 + m;
    }
    st = {s_end, st.v + st.a * d + p.jerk * d * d / 2, st.a + p.jerk * d, p.jerk};
    t0 += d;
  }
  return duration();
}

namespace {

// The acceleration part of a transition by `rise` ≥ 0, into phases [0, 3) with jerk sign `sign`.
void fill_rise(std::array<Phase, 7>& phases, int first, double rise, double sign, const MotionLimits& m) {
  const double A = m.acceleration, J = m.jerk;
  if (rise * J >= A * A) {
    phases[first] = {A / J, sign * J};
    phases[first + 1] = {(rise - A * A / J) / A, 0};
    phases[first + 2] = {A / J, -sign * J};
  } else {
    const double t = std::sqrt(std::max(rise, 0.0) / J);
    phases[first] = {t, sign * J};
    phases[first + 1] = {0, 0};
    phases[first + 2] = {t, -sign * J};
  }
}

}  // namespace

DoubleS plan_double_s(double v_start, double v_end, double length, const MotionLimits& limits) {
  const double V = limits.speed, A = limits.acceleration, J = limits.jerk;
  if (!(V > 0) || !(A > 0) || !(J > 0) || !(length >= 0) || !(v_start >= 0) || !(v_end >= 0))
    throw std::invalid_argument("plan_double_s: limits must be positive, speeds and length non-negative");
  v_start = std::min(v_start, V);
  v_end = std::min(v_end, V);
  const double needed = speed_change_distance(v_start, v_end, A, J);
  if (needed > length * (1 + 1e-9) + 1e-12)
    throw std::invalid_argument("plan_double_s: the speed change from " + std::to_string(v_start) + " to " + std::to_string(v_end) +
                                " needs " + std::to_string(needed) + " but the length is " + std::to_string(length));
  DoubleS plan;
  plan.v_start = v_start;
  plan.v_end = v_end;
  plan.length = length;
  auto covered = [&](double peak) { return speed_change_distance(v_start, peak, A, J) + speed_change_distance(v_end, peak, A, J); };
  double peak = V;
  if (covered(V) > length) {
    // covered() rises with the peak: bisect to the last bit.
    double lo = std::max(v_start, v_end), hi = V;
    for (int i = 0; i < 200; ++i) {
      const double m = 0.5 * (lo + hi);
      if (m <= lo || m >= hi) break;
      (covered(m) > length ? hi : lo) = m;
    }
    peak = lo;
  }
  plan.v_peak = peak;
  fill_rise(plan.phases, 0, peak - v_start, +1, limits);
  fill_rise(plan.phases, 4, peak - v_end, -1, limits);
  plan.phases[3] = {peak > 0 ? std::max(0.0, (length - covered(peak)) / peak) : 0.0, 0};
  return plan;
}

}  // namespace drom::machine
