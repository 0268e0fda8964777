#include "machine/kinematics.hpp"

#include <Eigen/Geometry>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdint>
#include <cstdio>
#include <limits>
#include <numbers>

namespace drom::machine {

namespace {

constexpr double kPi = std::numbers::pi;

// Inlined by force: it is the inner loop of every pose (a call per rotation cost 10 % of a path's IK).
[[gnu::always_inline]] inline Eigen::Vector3d rotate(const Eigen::Vector3d& k, double c, double s, const Eigen::Vector3d& x) {
  return x * c + k.cross(x) * s + k * (k.dot(x) * (1 - c));
}
Eigen::Vector3d rotate(const Eigen::Vector3d& k, double angle, const Eigen::Vector3d& x) { return rotate(k, std::cos(angle), std::sin(angle), x); }

}  // namespace

Kinematics::Kinematics(const Machine& machine) : machine_(machine) {
  for (int r = 0; r < machine_.rotary_count(); ++r) (machine_.rotary[r].on_table ? table_joints_ : head_joints_).push_back(3 + r);
  tip_controlled_ = head_joints_.empty();
  const auto dir = [&](int joint) { return machine_.rotary[joint - 3].direction; };
  switch (machine_.chain) {
    case KinematicChain::ThreeAxis: return;
    case KinematicChain::TableTable:  // R_t1 R_t2 u = e_z
      k1_ = dir(3), k2_ = dir(4), v_is_tool_axis_ = true;
      break;
    case KinematicChain::HeadHead:  // R_h1 R_h2 e_z = u
      k1_ = dir(3), k2_ = dir(4), v_is_tool_axis_ = false;
      break;
    case KinematicChain::TableHead:  // R_h(-θh) R_t(θt) u = e_z: k1 is the head's axis, k2 the table's
      k1_ = dir(4), k2_ = dir(3), v_is_tool_axis_ = true;
      break;
  }
  k1xk2_ = k1_.cross(k2_);
  k1k2_ = k1_.dot(k2_);
  cross_norm2_ = k1xk2_.squaredNorm();
}

ClPose Kinematics::forward(const Joints& q) const {
  const Machine& m = machine_;
  // The tool axis and tip relative to the pivot, turned by the head's joints (innermost first).
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d tip = Eigen::Vector3d::Zero();
  if (!tip_controlled_) {
    tip = -(m.pivot_length + m.tool_length) * Eigen::Vector3d::UnitZ();
    for (auto it = head_joints_.rbegin(); it != head_joints_.rend(); ++it) {
      const RotaryJoint& r = m.rotary[*it - 3];
      axis = rotate(r.direction, q[*it], axis);
      tip = r.point + rotate(r.direction, q[*it], tip - r.point);
    }
  }
  tip += q.head<3>();
  // Back through the table's joints (outermost first) into the part frame.
  for (int j : table_joints_) {
    const RotaryJoint& r = m.rotary[j - 3];
    axis = rotate(r.direction, -q[j], axis);
    tip = r.point + rotate(r.direction, -q[j], tip - r.point);
  }
  return {tip - m.part_origin, axis};
}

namespace {

using Turn = Kinematics::Turn;

// The rotation about k taking p to q (both projected on k's normal plane), as its angle and its
// cosine and sine (read off the projections, so positions need no trigonometric round trip).
Turn turn_about(const Eigen::Vector3d& k, const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  const Eigen::Vector3d pp = p - k * k.dot(p), qq = q - k * k.dot(q);
  const double c = pp.dot(qq), s = k.dot(pp.cross(qq)), r = std::sqrt(c * c + s * s);
  if (!(r > 0)) return {};
  return {std::atan2(s, c), c / r, s / r};
}
Turn turn_of(double angle) { return {angle, std::cos(angle), std::sin(angle)}; }
Turn reversed(const Turn& t) { return {t.angle == -kPi ? kPi : -t.angle, t.c, -t.s}; }

}  // namespace

BranchSplit Kinematics::split(const ClPose& pose) const {
  BranchSplit out;
  if (machine_.chain == KinematicChain::ThreeAxis) {
    out.count = (pose.axis - Eigen::Vector3d::UnitZ()).norm() < 1e-9 ? 1 : 0;
    out.c = {Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitZ()};
    return out;
  }
  const Eigen::Vector3d v = v_is_tool_axis_ ? pose.axis : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d w = v_is_tool_axis_ ? Eigen::Vector3d::UnitZ() : pose.axis;
  const double kv = k2_.dot(v), kw = k1_.dot(w);
  if ((v - k2_ * kv).squaredNorm() < 1e-24 || (w - k1_ * kw).squaredNorm() < 1e-24) {
    out.singular = true;
    out.count = 1;
    out.c = {v, v};
    return out;
  }
  const double denom = k1k2_ * k1k2_ - 1;
  const double alpha = (k1k2_ * kv - kw) / denom, beta = (k1k2_ * kw - kv) / denom;
  const double g2 = (1 - alpha * alpha - beta * beta - 2 * alpha * beta * k1k2_) / cross_norm2_;
  if (g2 < -1e-12) return out;
  const double gamma = std::sqrt(std::max(0.0, g2));
  out.count = gamma > 0 ? 2 : 1;
  const Eigen::Vector3d base = alpha * k1_ + beta * k2_;
  out.c = {base + gamma * k1xk2_, base - gamma * k1xk2_};
  return out;
}

Joints Kinematics::joints_from_turns(const ClPose& pose, const Turn& t1, const Turn& t2) const {
  const Machine& m = machine_;
  // The turn of each rotary joint (the head's angle enters a table-head chain as R_h(-θh)).
  std::array<Turn, 2> joint{};
  if (m.chain == KinematicChain::TableHead) joint = {t2, reversed(t1)};
  else if (m.chain != KinematicChain::ThreeAxis) joint = {t1, t2};
  Joints q = Joints::Zero();
  for (int r = 0; r < m.rotary_count(); ++r) q[3 + r] = joint[static_cast<std::size_t>(r)].angle;
  // Positions: the part point through the table's joints (innermost first), less the head's reach.
  Eigen::Vector3d tip = pose.tip + m.part_origin;
  for (auto it = table_joints_.rbegin(); it != table_joints_.rend(); ++it) {
    const RotaryJoint& rj = m.rotary[*it - 3];
    const Turn& t = joint[static_cast<std::size_t>(*it - 3)];
    tip = rj.point + rotate(rj.direction, t.c, t.s, tip - rj.point);
  }
  if (!tip_controlled_) {
    Eigen::Vector3d reach = -(m.pivot_length + m.tool_length) * Eigen::Vector3d::UnitZ();
    for (auto it = head_joints_.rbegin(); it != head_joints_.rend(); ++it) {
      const RotaryJoint& rj = m.rotary[*it - 3];
      const Turn& t = joint[static_cast<std::size_t>(*it - 3)];
      reach = rj.point + rotate(rj.direction, t.c, t.s, reach - rj.point);
    }
    tip -= reach;
  }
  q.head<3>() = tip;
  return q;
}

Joints Kinematics::solve_branch(const ClPose& pose, const BranchSplit& split, int branch) const {
  if (machine_.chain == KinematicChain::ThreeAxis) return joints_from_turns(pose, {}, {});
  const Eigen::Vector3d v = v_is_tool_axis_ ? pose.axis : Eigen::Vector3d::UnitZ();
  const Eigen::Vector3d w = v_is_tool_axis_ ? Eigen::Vector3d::UnitZ() : pose.axis;
  const Eigen::Vector3d& c = split.c[static_cast<std::size_t>(branch)];
  return joints_from_turns(pose, turn_about(k1_, c, w), turn_about(k2_, v, c));
}

IkBranches Kinematics::inverse(const ClPose& pose, double free_angle) const {
  IkBranches out;
  const BranchSplit sp = split(pose);
  out.count = sp.count;
  out.singular = sp.singular;
  if (sp.singular) {
    // One angle is free. With θ2 free, c = v; with θ1 free, c = w.
    const Eigen::Vector3d v = v_is_tool_axis_ ? pose.axis : Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d w = v_is_tool_axis_ ? Eigen::Vector3d::UnitZ() : pose.axis;
    Turn t1 = turn_of(free_angle), t2 = turn_of(free_angle);
    if ((v - k2_ * k2_.dot(v)).squaredNorm() < 1e-24) t1 = turn_about(k1_, v, w);
    else t2 = turn_about(k2_, v, w);
    // Reachable only if the fixed angle brings v onto w.
    const Eigen::Vector3d reached = rotate(k1_, t1.c, t1.s, rotate(k2_, t2.c, t2.s, v));
    out.count = (reached - w).norm() < 1e-9 ? 1 : 0;
    if (out.count) out.joints[0] = joints_from_turns(pose, t1, t2);
    return out;
  }
  for (int b = 0; b < out.count; ++b) out.joints[static_cast<std::size_t>(b)] = solve_branch(pose, sp, b);
  return out;
}

double Kinematics::singularity_distance(const Eigen::Vector3d& axis) const {
  if (machine_.chain == KinematicChain::ThreeAxis) return kPi / 2;
  const Eigen::Vector3d& k = v_is_tool_axis_ ? k2_ : k1_;
  const double c = std::min(1.0, std::abs(k.dot(axis)) / axis.norm());
  double d = std::acos(c);
  // The fixed vector e_z along the other axis is a singularity of every pose (a head axis that is vertical).
  const Eigen::Vector3d& other = v_is_tool_axis_ ? k1_ : k2_;
  if (std::abs(other.z()) > 1 - 1e-12) d = 0;
  return d;
}

std::optional<Eigen::Vector3d> Kinematics::singular_direction() const {
  if (machine_.chain == KinematicChain::ThreeAxis) return std::nullopt;
  const Eigen::Vector3d& other = v_is_tool_axis_ ? k1_ : k2_;
  if (std::abs(other.z()) > 1 - 1e-12) return std::nullopt;
  return (v_is_tool_axis_ ? k2_ : k1_).normalized();
}

double Kinematics::stroke_value(int j, const Joints& q) const { return j == 2 && tip_controlled_ ? q[2] + machine_.tool_length : q[j]; }

double joint_in_program_units(const Machine& m, int j, double value) { return m.axes[j].rotary ? value * 180 / kPi : value; }

std::string describe_joint_value(const Machine& m, int j, double value) {
  char buf[96];
  const AxisLimits& a = m.axes[j];
  if (a.rotary) std::snprintf(buf, sizeof buf, "%c = %.4f deg", a.name, value * 180 / kPi);
  else std::snprintf(buf, sizeof buf, "%c = %.4f mm", a.name, value);
  return buf;
}

namespace {

std::string stroke_text(const Machine& m, int j) {
  const AxisLimits& a = m.axes[j];
  char buf[96];
  const double u = a.rotary ? 180 / kPi : 1.0;
  std::snprintf(buf, sizeof buf, "[%g, %g] %s", a.min * u, a.max * u, a.rotary ? "deg" : "mm");
  return buf;
}

// The turn of `angle` nearest `reference` that lies within the stroke; NaN when none does.
double unwind(double angle, double reference, const AxisLimits& a) {
  const double base = angle + 2 * kPi * std::round((reference - angle) / (2 * kPi));
  if (a.within(base)) return base;
  double best = std::numeric_limits<double>::quiet_NaN();
  for (int k = -3; k <= 3; ++k) {
    const double c = base + 2 * kPi * k;
    if (a.within(c) && (std::isnan(best) || std::abs(c - reference) < std::abs(best - reference))) best = c;
  }
  return best;
}

}  // namespace

namespace {

// One pose's choice between its branches, as a path would make it: within the strokes first, then
// the least motion from the previous pose (time-weighted, the slowest rotary axis's), rotary angles
// unwound to the turn nearest the previous one.
struct Choice {
  int branch = -1;
  Joints joints = Joints::Zero();
  std::vector<JointPath::Violation> faults;
};

Choice choose(const Kinematics& kin, std::size_t i, IkBranches s, const Joints& previous, bool have_previous) {
  const Machine& m = kin.machine();
  Choice best;
  double best_cost = 0;
  for (int b = 0; b < s.count; ++b) {
    Joints& q = s.joints[static_cast<std::size_t>(b)];
    std::vector<JointPath::Violation> faults;
    double cost = 0;
    for (int j = 3; j < m.joint_count(); ++j) {
      const double reference = have_previous ? previous[j] : 0.0;
      const double u = unwind(q[j], reference, m.axes[j]);
      if (std::isnan(u)) faults.push_back({i, j, q[j], describe_joint_value(m, j, q[j]) + " (any turn) beyond its stroke " + stroke_text(m, j)});
      else q[j] = u;
      cost = std::max(cost, std::abs(q[j] - reference) / m.axes[j].velocity);
    }
    for (int j = 0; j < 3; ++j) {
      const double value = kin.stroke_value(j, q);
      if (!m.axes[j].within(value, 1e-6))
        faults.push_back({i, j, value,
                          describe_joint_value(m, j, value) + (j == 2 && kin.tip_controlled() ? " (gauge line: Z + tool length)" : "") + " beyond its stroke " +
                              stroke_text(m, j)});
    }
    if (best.branch < 0 || faults.size() < best.faults.size() || (faults.size() == best.faults.size() && cost < best_cost - 1e-15)) {
      best.branch = b;
      best.joints = q;
      best.faults = std::move(faults);
      best_cost = cost;
    }
  }
  return best;
}

// Whether the joints, each rotary one at its turn nearest `previous`, stay within every stroke
// (unwinding them in place). A rotary axis that would have to take another turn to stay in its
// stroke is not: the other branch may be the better way on.
bool unwound_within(const Kinematics& kin, Joints& q, const Joints& previous) {
  const Machine& m = kin.machine();
  for (int j = 3; j < m.joint_count(); ++j) {
    const double u = unwind(q[j], previous[j], m.axes[j]);
    if (std::isnan(u) || std::abs(u - previous[j]) > kPi) return false;
    q[j] = u;
  }
  for (int j = 0; j < 3; ++j)
    if (!m.axes[j].within(kin.stroke_value(j, q), 1e-6)) return false;
  return true;
}

}  // namespace

JointPath inverse_path(const Kinematics& kin, std::span<const ClPose> poses, const Joints* start) {
  const Machine& m = kin.machine();
  const std::size_t n = poses.size();
  JointPath path;
  path.joints.resize(n);
  path.branch.assign(n, 0);
  path.singularity_distance.resize(n);
  // What each pose's subproblem gave, in a byte: its status, and which of its branches continues each
  // branch of the pose before (the one whose c moves least). Computed in parallel; following the branch
  // along the path is then a walk over bits. (Keeping each pose's BranchSplit, 56 bytes, cost more in
  // first touches of memory than recomputing the few needed again.)
  enum : std::uint8_t { kOutOfReach = 0, kRegular = 1, kSingular = 2, kStatusMask = 3, kFromBranch0 = 4, kFromBranch1 = 8 };
  std::vector<std::uint8_t> status(n);
  auto status_of = [](const BranchSplit& sp) -> std::uint8_t { return sp.count == 0 ? kOutOfReach : sp.singular ? kSingular : kRegular; };
  auto nearest = [](const BranchSplit& sp, const Eigen::Vector3d& c) { return sp.count == 2 && (sp.c[1] - c).squaredNorm() < (sp.c[0] - c).squaredNorm() ? 1 : 0; };
  tbb::parallel_for(tbb::blocked_range<std::size_t>(0, n), [&](const tbb::blocked_range<std::size_t>& r) {
    BranchSplit before = r.begin() > 0 ? kin.split(poses[r.begin() - 1]) : BranchSplit{};
    for (std::size_t i = r.begin(); i < r.end(); ++i) {
      const BranchSplit sp = kin.split(poses[i]);
      std::uint8_t bits = status_of(sp);
      if (sp.count > 0 && before.count > 0)
        bits |= static_cast<std::uint8_t>((nearest(sp, before.c[0]) ? kFromBranch0 : 0) | (nearest(sp, before.c[1]) ? kFromBranch1 : 0));
      status[i] = bits;
      before = sp;
    }
  });
  // 1. The continuous branch from pose `from` on, given the c of the reachable pose before it. Past an
  // unreachable pose the branch is weighed against the last reachable one's c again.
  auto follow = [&](std::size_t from, const Eigen::Vector3d& c_from) {
    std::size_t last = n;  // the last reachable pose walked, n: none yet (then c_from)
    for (std::size_t i = from; i < n; ++i) {
      if ((status[i] & kStatusMask) == kOutOfReach) continue;
      if (last != n && last == i - 1) {
        path.branch[i] = (status[i] & (path.branch[last] ? kFromBranch1 : kFromBranch0)) ? 1 : 0;
      } else {
        const Eigen::Vector3d c = last == n ? c_from : kin.split(poses[last]).c[static_cast<std::size_t>(path.branch[last])];
        path.branch[i] = nearest(kin.split(poses[i]), c);
      }
      last = i;
    }
  };
  // 2. That branch's joints (in parallel), and each pose's distance to the singularity.
  auto solve = [&](std::size_t from) {
    tbb::parallel_for(from, n, [&](std::size_t i) {
      if ((status[i] & kStatusMask) == kRegular) path.joints[i] = kin.solve_branch(poses[i], kin.split(poses[i]), path.branch[i]);
      path.singularity_distance[i] = kin.singularity_distance(poses[i].axis);
    });
  };
  bool have_previous = start != nullptr;
  Joints previous = start ? *start : Joints::Zero();
  std::size_t first = 0;
  if (start) {
    const BranchSplit sp = kin.split(kin.forward(*start));
    follow(0, sp.c[0]);
  } else if (n > 0) {
    // The first pose: both branches weighed; the path follows from the one taken.
    const BranchSplit sp = kin.split(poses[0]);
    const IkBranches s = kin.inverse(poses[0]);
    if (s.count > 0) {
      Choice c = choose(kin, 0, s, previous, false);
      path.branch[0] = c.branch;
      follow(1, sp.c[static_cast<std::size_t>(c.branch)]);
    } else {
      follow(1, sp.c[0]);
    }
    first = 0;
  }
  solve(first);
  // 4. In order: unwind, and where the continuous branch leaves a stroke, is singular or out of reach,
  // weigh both branches; when that changes the branch, the rest of the path follows the new one.
  const int free_joint = m.chain == KinematicChain::TableTable ? 4 : 3;  // free at the singularity: C of a table-table chain, the outer axis otherwise
  for (std::size_t i = 0; i < n; ++i) {
    Joints q = path.joints[i];
    if ((status[i] & kStatusMask) == kRegular && (i > 0 || have_previous) && unwound_within(kin, q, previous)) {
      path.joints[i] = q;
      previous = q;
      have_previous = true;
      continue;
    }
    const IkBranches s = kin.inverse(poses[i], have_previous ? previous[free_joint] : 0.0);
    if (s.count == 0) {
      path.violations.push_back({i, -1, 0, "the tool axis cannot be reached by the rotary axes of " + m.name});
      path.joints[i] = previous;
      continue;
    }
    Choice c = choose(kin, i, s, previous, have_previous);
    for (auto& f : c.faults) path.violations.push_back(std::move(f));
    const BranchSplit sp = kin.split(poses[i]);
    path.joints[i] = c.joints;
    previous = c.joints;
    have_previous = true;
    if (!sp.singular && c.branch != path.branch[i]) {
      path.branch[i] = c.branch;
      follow(i + 1, sp.c[static_cast<std::size_t>(c.branch)]);
      solve(i + 1);
    } else if (sp.singular && i + 1 < n && (status[i + 1] & kStatusMask) != kSingular) {
      // Past the singularity the branch whose c continues from the free angle's pose is the continuous
      // one. Within a run of singular poses (a 3+2 program along C's axis) nothing is followed: each is
      // solved here from the one before, and following and solving the rest of the path again at every
      // one of them made a vertical packet's program quadratic in its length.
      follow(i + 1, kin.split(kin.forward(c.joints)).c[0]);
      solve(i + 1);
    }
  }
  return path;
}

}  // namespace drom::machine
