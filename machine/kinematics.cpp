#include "machine/kinematics.hpp"

#include <Eigen/Geometry>
#include <tbb/parallel_for.h>

#include <cmath>
#include <cstdio>
#include <limits>
#include <numbers>

namespace drom::machine {

namespace {

constexpr double kPi = std::numbers::pi;

Eigen::Vector3d rotate(const Eigen::Vector3d& k, double c, double s, const Eigen::Vector3d& x) {
  return x * c + k.cross(x) * s + k * (k.dot(x) * (1 - c));
}
Eigen::Vector3d rotate(const Eigen::Vector3d& k, double angle, const Eigen::Vector3d& x) { return rotate(k, std::cos(angle), std::sin(angle), x); }

// The angle about k taking p to q (both projected on k's normal plane); `degenerate` when p lies along k.
double angle_about(const Eigen::Vector3d& k, const Eigen::Vector3d& p, const Eigen::Vector3d& q) {
  const Eigen::Vector3d pp = p - k * k.dot(p), qq = q - k * k.dot(q);
  return std::atan2(k.dot(pp.cross(qq)), pp.dot(qq));
}

double wrap(double a) {  // to (-π, π]
  a = std::remainder(a, 2 * kPi);
  return a <= -kPi ? a + 2 * kPi : a;
}

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

IkBranches Kinematics::inverse(const ClPose& pose, double free_angle) const {
  const Machine& m = machine_;
  IkBranches out;
  std::array<std::array<double, 2>, 2> angles{};  // [branch][θ1, θ2]
  if (m.chain == KinematicChain::ThreeAxis) {
    out.count = (pose.axis - Eigen::Vector3d::UnitZ()).norm() < 1e-9 ? 1 : 0;
  } else {
    const Eigen::Vector3d v = v_is_tool_axis_ ? pose.axis : Eigen::Vector3d::UnitZ();
    const Eigen::Vector3d w = v_is_tool_axis_ ? Eigen::Vector3d::UnitZ() : pose.axis;
    const double v_off = (v - k2_ * k2_.dot(v)).norm(), w_off = (w - k1_ * k1_.dot(w)).norm();
    if (v_off < 1e-12 || w_off < 1e-12) {
      // One angle is free. With θ2 free, c = v; with θ1 free, c = w.
      out.singular = true;
      double t1 = free_angle, t2 = free_angle;
      if (v_off < 1e-12) t1 = angle_about(k1_, v, w);
      else t2 = angle_about(k2_, v, w);
      // Reachable only if the fixed angle brings v onto w.
      const Eigen::Vector3d reached = rotate(k1_, t1, rotate(k2_, t2, v));
      out.count = (reached - w).norm() < 1e-9 ? 1 : 0;
      angles[0] = {t1, t2};
    } else {
      const double denom = k1k2_ * k1k2_ - 1;
      const double alpha = (k1k2_ * k2_.dot(v) - k1_.dot(w)) / denom;
      const double beta = (k1k2_ * k1_.dot(w) - k2_.dot(v)) / denom;
      const double g2 = (1 - alpha * alpha - beta * beta - 2 * alpha * beta * k1k2_) / cross_norm2_;
      if (g2 >= -1e-12) {
        const double gamma = std::sqrt(std::max(0.0, g2));
        out.count = gamma > 0 ? 2 : 1;
        for (int b = 0; b < out.count; ++b) {
          const Eigen::Vector3d c = alpha * k1_ + beta * k2_ + (b == 0 ? gamma : -gamma) * k1xk2_;
          angles[b] = {angle_about(k1_, c, w), angle_about(k2_, v, c)};
        }
      }
    }
  }
  for (int b = 0; b < out.count; ++b) {
    Joints q = Joints::Zero();
    if (m.chain == KinematicChain::TableHead) {
      q[4] = wrap(-angles[b][0]);  // the head's angle enters as R_h(-θh)
      q[3] = wrap(angles[b][1]);
    } else if (m.chain != KinematicChain::ThreeAxis) {
      q[3] = wrap(angles[b][0]);
      q[4] = wrap(angles[b][1]);
    }
    // Positions: the part point through the table's joints (innermost first), less the head's reach.
    Eigen::Vector3d tip = pose.tip + m.part_origin;
    for (auto it = table_joints_.rbegin(); it != table_joints_.rend(); ++it) {
      const RotaryJoint& r = m.rotary[*it - 3];
      tip = r.point + rotate(r.direction, q[*it], tip - r.point);
    }
    if (!tip_controlled_) {
      Eigen::Vector3d reach = -(m.pivot_length + m.tool_length) * Eigen::Vector3d::UnitZ();
      for (auto it = head_joints_.rbegin(); it != head_joints_.rend(); ++it) {
        const RotaryJoint& r = m.rotary[*it - 3];
        reach = r.point + rotate(r.direction, q[*it], reach - r.point);
      }
      tip -= reach;
    }
    q.head<3>() = tip;
    out.joints[b] = q;
  }
  return out;
}

double Kinematics::singularity_distance(const Eigen::Vector3d& axis) const {
  if (machine_.chain == KinematicChain::ThreeAxis) return kPi / 2;
  const Eigen::Vector3d& k = v_is_tool_axis_ ? k2_ : k1_;
  const double c = std::min(1.0, std::abs(k.dot(axis.normalized())));
  double d = std::acos(c);
  // The fixed vector e_z along the other axis is a singularity of every pose (a head axis that is vertical).
  const Eigen::Vector3d& other = v_is_tool_axis_ ? k1_ : k2_;
  if (std::abs(other.z()) > 1 - 1e-12) d = 0;
  return d;
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

JointPath inverse_path(const Kinematics& kin, std::span<const ClPose> poses, const Joints* start) {
  const Machine& m = kin.machine();
  const int nj = m.joint_count();
  JointPath path;
  path.joints.resize(poses.size());
  path.branch.assign(poses.size(), 0);
  path.singularity_distance.resize(poses.size());
  std::vector<IkBranches> solved(poses.size());
  tbb::parallel_for(std::size_t(0), poses.size(), [&](std::size_t i) {
    solved[i] = kin.inverse(poses[i]);
    path.singularity_distance[i] = kin.singularity_distance(poses[i].axis);
  });

  bool have_previous = start != nullptr;
  Joints previous = start ? *start : Joints::Zero();
  for (std::size_t i = 0; i < poses.size(); ++i) {
    IkBranches& s = solved[i];
    if (s.singular && have_previous) {
      // The free angle keeps its previous value: solve again with it. It is the inner table axis of a
      // table-table chain (C), the outer head axis of a head-head one, the table axis of a table-head one.
      const int free_joint = m.chain == KinematicChain::TableTable ? 4 : 3;
      s = kin.inverse(poses[i], previous[free_joint]);
    }
    if (s.count == 0) {
      path.violations.push_back({i, -1, 0, "the tool axis cannot be reached by the rotary axes of " + m.name});
      path.joints[i] = previous;
      continue;
    }
    // Unwind each branch's rotary angles, count its stroke violations, and cost its motion from the previous pose.
    int best = -1;
    std::size_t best_faults = 0;
    double best_cost = 0;
    std::array<std::vector<JointPath::Violation>, 2> faults;
    for (int b = 0; b < s.count; ++b) {
      Joints& q = s.joints[b];
      double cost = 0;
      for (int j = 3; j < nj; ++j) {
        const double reference = have_previous ? previous[j] : 0.0;
        const double u = unwind(q[j], reference, m.axes[j]);
        if (std::isnan(u)) {
          faults[b].push_back({i, j, q[j], describe_joint_value(m, j, q[j]) + " (any turn) beyond its stroke " + stroke_text(m, j)});
        } else {
          q[j] = u;
        }
        cost = std::max(cost, std::abs(q[j] - reference) / m.axes[j].velocity);
      }
      for (int j = 0; j < 3; ++j) {
        const double value = kin.stroke_value(j, q);
        if (!m.axes[j].within(value, 1e-6))
          faults[b].push_back({i, j, value,
                               describe_joint_value(m, j, value) + (j == 2 && kin.tip_controlled() ? " (gauge line: Z + tool length)" : "") +
                                   " beyond its stroke " + stroke_text(m, j)});
      }
      if (best < 0 || faults[b].size() < best_faults || (faults[b].size() == best_faults && cost < best_cost - 1e-15)) {
        best = b;
        best_faults = faults[b].size();
        best_cost = cost;
      }
    }
    path.joints[i] = s.joints[best];
    path.branch[i] = best;
    for (auto& f : faults[best]) path.violations.push_back(std::move(f));
    previous = s.joints[best];
    have_previous = true;
  }
  return path;
}

}  // namespace drom::machine
