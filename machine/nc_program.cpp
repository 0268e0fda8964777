#include "machine/nc_program.hpp"

#include <cmath>
#include <numbers>

namespace drom::machine {

PlaneAxes plane_axes(int plane) {
  switch (plane) {
    case 18: return {2, 0, 1};  // ZX: the first coordinate is Z, so counter-clockwise is seen from +Y
    case 19: return {1, 2, 0};  // YZ, seen from +X
    default: return {0, 1, 2};  // XY, seen from +Z
  }
}

double arc_sweep(const NcMove& m) {
  const PlaneAxes p = plane_axes(m.plane);
  const double a0 = std::atan2(m.start[p.second] - m.centre[p.second], m.start[p.first] - m.centre[p.first]);
  const double a1 = std::atan2(m.end[p.second] - m.centre[p.second], m.end[p.first] - m.centre[p.first]);
  constexpr double two_pi = 2 * std::numbers::pi;
  double sweep = a1 - a0;
  const int extra = std::max(0, std::abs(m.rotation) - 1);
  if (m.rotation >= 0) {
    while (sweep <= 1e-12) sweep += two_pi;  // a full circle when the ends coincide
    return sweep + two_pi * extra;
  }
  while (sweep >= -1e-12) sweep -= two_pi;
  return sweep - two_pi * extra;
}

double arc_length(const NcMove& m) {
  const PlaneAxes p = plane_axes(m.plane);
  const double r = std::hypot(m.start[p.first] - m.centre[p.first], m.start[p.second] - m.centre[p.second]);
  return std::hypot(r * arc_sweep(m), m.end[p.normal] - m.start[p.normal]);
}

double NcMove::reference_length() const {
  const double xyz = type == MoveType::Arc ? arc_length(*this) : (end.head<3>() - start.head<3>()).norm();
  if (xyz > 1e-12) return xyz;
  return (end.tail<3>() - start.tail<3>()).norm();
}

double NcMove::programmed_duration() const {
  if (type == MoveType::Dwell) return dwell;
  if (type == MoveType::Rapid || !(feed > 0)) return 0;
  if (feed_mode == FeedMode::InverseTime) return 60.0 / feed;
  return 60.0 * reference_length() / feed;
}

bool NcProgram::uses_rotary(int axis) const {
  for (const NcMove& m : moves)
    if (std::abs(m.end[axis]) > 1e-9 || std::abs(m.start[axis]) > 1e-9) return true;
  return false;
}

}  // namespace drom::machine
