#include "machine/machine_program.hpp"

#include "support/input_error.hpp"

#include <cmath>
#include <numbers>

namespace drom::machine {

namespace {

struct ArcShape {
  double a0 = 0, sweep = 0, r0 = 0, r1 = 0, rise = 0;  // start angle, sweep, radii, travel along the normal
  PlaneAxes p;
};

ArcShape arc_shape(const MachineBlock& b) {
  ArcShape a;
  a.p = plane_axes(b.plane);
  NcMove m;
  m.plane = b.plane;
  m.rotation = b.rotation;
  m.centre = b.centre;
  m.start.head<3>() = b.start.head<3>();
  m.end.head<3>() = b.end.head<3>();
  a.sweep = arc_sweep(m);
  a.a0 = std::atan2(b.start[a.p.second] - b.centre[a.p.second], b.start[a.p.first] - b.centre[a.p.first]);
  a.r0 = std::hypot(b.start[a.p.first] - b.centre[a.p.first], b.start[a.p.second] - b.centre[a.p.second]);
  a.r1 = std::hypot(b.end[a.p.first] - b.centre[a.p.first], b.end[a.p.second] - b.centre[a.p.second]);
  a.rise = b.end[a.p.normal] - b.start[a.p.normal];
  return a;
}

// Whether the angle range between a and b (either order) holds offset + k π for some integer k.
bool holds(double a, double b, double offset) {
  const double lo = std::min(a, b) - offset, hi = std::max(a, b) - offset;
  return std::floor(hi / std::numbers::pi) >= std::ceil(lo / std::numbers::pi);
}

}  // namespace

MachineProgram to_machine_program(const NcProgram& program, const Machine& machine) {
  MachineProgram out;
  out.origin = program.origin;
  constexpr double kDegree = std::numbers::pi / 180;
  // The joint of each program axis X Y Z A B C (-1: the machine lacks it).
  std::array<int, 6> joint{};
  for (int k = 0; k < 6; ++k) joint[k] = machine.joint_of(kProgramAxisLetters[k]);
  for (const NcMove& m : program.moves) {
    for (int k = 3; k < 6; ++k) {
      if (joint[k] >= 0) continue;
      if (std::abs(m.end[k]) > 1e-9 || std::abs(m.start[k]) > 1e-9) {
        const std::string letters = machine.rotary_letters();
        throw InputError(program.origin + ":" + std::to_string(m.line) + ": the program moves " + kProgramAxisLetters[k] + " to " +
                         std::to_string(m.end[k]) + " deg, but machine '" + machine.name + "' has " +
                         (letters.empty() ? std::string("no rotary axis (3-axis)") : "rotary axes " + letters + " only") + " (" + machine.origin + ")");
      }
    }
    MachineBlock b;
    b.type = m.type;
    for (int k = 0; k < 6; ++k) {
      if (joint[k] < 0) continue;
      const double unit = k < 3 ? 1.0 : kDegree;
      b.start[joint[k]] = m.start[k] * unit;
      b.end[joint[k]] = m.end[k] * unit;
    }
    b.plane = m.plane;
    b.centre = m.centre;
    b.rotation = m.rotation;
    b.programmed_duration = m.programmed_duration();
    b.blend_tolerance = m.control == PathControl::Blend ? m.blend_tolerance : 0;
    b.stop_before = m.stop_before;
    b.line = m.line;
    out.blocks.push_back(b);
  }
  return out;
}

Joints block_joints_at(const MachineBlock& b, double sigma) {
  Joints q = b.start + sigma * (b.end - b.start);
  if (b.type == MoveType::Arc) {
    const ArcShape a = arc_shape(b);
    const double r = a.r0 + sigma * (a.r1 - a.r0);  // the ends' radii differ by the program's rounding
    const double angle = a.a0 + sigma * a.sweep;
    q[a.p.first] = b.centre[a.p.first] + r * std::cos(angle);
    q[a.p.second] = b.centre[a.p.second] + r * std::sin(angle);
  }
  return q;
}


BlockPath::Derivatives BlockPath::at(const MachineBlock& b, double sigma) const {
  Derivatives d;
  if (!(length > 0)) {
    d.q = b.start + sigma * (b.end - b.start);
    return d;
  }
  d.q = b.start + sigma * (b.end - b.start);
  d.d1 = (b.end - b.start) / length;
  if (b.type != MoveType::Arc) return d;
  const ArcShape a = arc_shape(b);
  const double theta = a.a0 + sigma * a.sweep, r = a.r0 + sigma * (a.r1 - a.r0), w = a.sweep / length;
  const double c = std::cos(theta), s = std::sin(theta);
  d.q[a.p.first] = b.centre[a.p.first] + r * c;
  d.q[a.p.second] = b.centre[a.p.second] + r * s;
  d.d1[a.p.first] = -r * w * s, d.d1[a.p.second] = r * w * c;
  d.d2[a.p.first] = -r * w * w * c, d.d2[a.p.second] = -r * w * w * s;
  d.d3[a.p.first] = r * w * w * w * s, d.d3[a.p.second] = -r * w * w * w * c;
  return d;
}

BlockPath block_path(const MachineBlock& b, const Kinematics& kin) {
  BlockPath p;
  if (b.type == MoveType::Dwell) return p;
  const Joints dq = b.end - b.start;
  const Machine& m = kin.machine();
  auto rotary_travel_deg = [&]() {
    double t = 0;
    for (int j = 3; j < m.joint_count(); ++j) t += dq[j] * dq[j];
    return std::sqrt(t) * 180 / std::numbers::pi;
  };
  if (b.type == MoveType::Arc) {
    const ArcShape a = arc_shape(b);
    const double r = 0.5 * (a.r0 + a.r1);
    p.length = std::hypot(r * a.sweep, a.rise);
    if (!(p.length > 1e-12)) {
      p.length = rotary_travel_deg();
      p.rotary_only = true;
    }
    if (!(p.length > 0)) return p;
    p.arc_radius = r;
    p.arc_in_plane = r * std::abs(a.sweep) / p.length;
    p.rate_start = p.at(b, 0).d1;
    p.rate_end = p.at(b, 1).d1;
    p.rate_max = p.rate_start.cwiseAbs().cwiseMax(p.rate_end.cwiseAbs());
    const double a1 = a.a0 + a.sweep;
    const bool full = std::abs(a.sweep) >= 2 * std::numbers::pi;
    if (full || holds(a.a0, a1, 0)) p.rate_max[a.p.second] = p.arc_in_plane;                    // |cos θ| = 1 within the sweep
    if (full || holds(a.a0, a1, std::numbers::pi / 2)) p.rate_max[a.p.first] = p.arc_in_plane;  // |sin θ| = 1
    return p;
  }
  p.length = (kin.forward(b.end).tip - kin.forward(b.start).tip).norm();
  if (!(p.length > 1e-9)) {
    p.length = rotary_travel_deg();
    p.rotary_only = p.length > 0;
  }
  if (!(p.length > 0)) return p;
  p.rate_start = p.rate_end = dq / p.length;
  p.rate_max = p.rate_start.cwiseAbs();
  return p;
}

}  // namespace drom::machine
