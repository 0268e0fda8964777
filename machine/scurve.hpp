#pragma once
// The jerk-limited ("double S", 7-phase) speed transition along a path coordinate s, with zero
// acceleration at both ends: jerk ±J, |acceleration| ≤ A, speed ≤ V. Every regime is covered:
// A reached or not, V reached or not, asymmetric end speeds. Rest-to-rest over a length L it gives
// the closed forms of Herraz 2021 §1.6.2 (L/V + V/A + A/J; L/V + 2√(V/J); 4∛(L/(2J))) and the
// regime they leave out, A reached but V not.
#include <array>

namespace drom::machine {

struct MotionLimits {
  double speed = 0;         // V (units/s)
  double acceleration = 0;  // A (units/s²)
  double jerk = 0;          // J (units/s³)
};

// Time to change speed by `delta` ≥ 0 with a = 0 at both ends.
double speed_change_time(double delta, double acceleration, double jerk);
// Distance covered while changing speed from v0 to v1 (either order) with a = 0 at both ends.
double speed_change_distance(double v0, double v1, double acceleration, double jerk);
// The highest speed v1 ≤ cap reachable from v0 (a = 0 at both ends) within `distance`; v0 when distance ≤ 0.
double reachable_speed(double v0, double distance, double cap, double acceleration, double jerk);

// One phase of constant jerk.
struct Phase {
  double duration = 0, jerk = 0;
};

// A transition from v_start to v_end over `length`, rising to v_peak ≤ limits.speed and
// cruising there. Phases: up to 3 to accelerate, 1 cruise, up to 3 to decelerate (zero-length
// phases are kept, so the layout is fixed: indices 0-2 accelerate, 3 cruises, 4-6 decelerate).
struct DoubleS {
  double v_start = 0, v_end = 0, v_peak = 0, length = 0;
  std::array<Phase, 7> phases{};
  double duration() const;
  // Kinematic state at time t in [0, duration()] from the start: s, v, a, j.
  struct State {
    double s = 0, v = 0, a = 0, j = 0;
  };
  State at(double t) const;
  // The time at which s is reached (s in [0, length]).
  double time_at(double s) const;
};

// The fastest transition. Requires the end speeds to be compatible with the length
// (speed_change_distance(v_start, v_end) ≤ length, within rounding); throws std::invalid_argument otherwise.
DoubleS plan_double_s(double v_start, double v_end, double length, const MotionLimits& limits);

}  // namespace drom::machine
