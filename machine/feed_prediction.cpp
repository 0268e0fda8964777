#include "machine/feed_prediction.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

namespace drom::machine {

const char* feed_limit_name(FeedLimit limit) {
  switch (limit) {
    case FeedLimit::ProgrammedFeed: return "programmed_feed";
    case FeedLimit::AxisVelocity: return "velocity";
    case FeedLimit::InterpolationCycle: return "interpolation_cycle";
    case FeedLimit::AxisAcceleration: return "acceleration";
    case FeedLimit::AxisJerk: return "jerk";
    case FeedLimit::None: return "none";
  }
  return "?";
}

namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();

// What the planner knows of a block.
struct Limits {
  double cap = kInf;
  FeedLimit cap_source = FeedLimit::None;
  int cap_axis = -1;
  double acceleration = kInf, jerk = kInf;
  int acceleration_axis = -1, jerk_axis = -1;
};

Limits block_limits(const MachineBlock& b, const BlockPath& p, BlockPrediction& out, const Machine& m) {
  Limits l;
  const int nj = m.joint_count();
  for (int k = 0; k < nj; ++k) {
    const double rate = p.rate_max[k];
    if (!(rate > 1e-15)) continue;
    const AxisLimits& ax = m.axes[k];
    const double v = ax.velocity / rate, a = ax.acceleration / rate, j = ax.jerk / rate;
    if (v < out.path_limit[0]) out.path_limit[0] = v, out.limiting_axis[0] = k;
    if (a < out.path_limit[1]) out.path_limit[1] = a, out.limiting_axis[1] = k;
    if (j < out.path_limit[2]) out.path_limit[2] = j, out.limiting_axis[2] = k;
  }
  l.cap = out.path_limit[0], l.cap_source = FeedLimit::AxisVelocity, l.cap_axis = out.limiting_axis[0];
  l.acceleration = out.path_limit[1], l.acceleration_axis = out.limiting_axis[1];
  l.jerk = out.path_limit[2], l.jerk_axis = out.limiting_axis[2];
  if (b.type == MoveType::Arc && p.arc_radius > 0 && p.arc_in_plane > 0) {
    // Half of the in-plane axes' acceleration and jerk goes to turning: v² c² / R ≤ A/2, v³ c³ / R² ≤ J/2.
    const PlaneAxes pa = plane_axes(b.plane);
    for (int k : {pa.first, pa.second}) {
      const AxisLimits& ax = m.axes[k];
      const double c = p.arc_in_plane, R = p.arc_radius;
      const double v_acc = std::sqrt(0.5 * ax.acceleration * R) / c, v_jerk = std::cbrt(0.5 * ax.jerk * R * R) / c;
      if (v_acc < l.cap) l.cap = v_acc, l.cap_source = FeedLimit::AxisAcceleration, l.cap_axis = k;
      if (v_jerk < l.cap) l.cap = v_jerk, l.cap_source = FeedLimit::AxisJerk, l.cap_axis = k;
      l.acceleration = std::min(l.acceleration, 0.5 * ax.acceleration / c);
      l.jerk = std::min(l.jerk, 0.5 * ax.jerk / c);
    }
  }
  if (b.programmed_duration > 0 && b.type != MoveType::Rapid) {
    const double v = p.length / b.programmed_duration;
    if (v <= l.cap) l.cap = v, l.cap_source = FeedLimit::ProgrammedFeed, l.cap_axis = -1;
  }
  const double v_cycle = p.length / m.interpolation_cycle;
  if (v_cycle < l.cap) l.cap = v_cycle, l.cap_source = FeedLimit::InterpolationCycle, l.cap_axis = -1;
  return l;
}

// The corners between blocks, as the control rounds them (machine_definition.hpp's JunctionMode).
// At corner k, axis j's rate dq_j/ds jumps by Δu_j. The control replaces the corner by a blend of
// half-length δ, the longest that keeps every axis within its tolerance ε_j and within half of each
// neighbouring block. Within it, the axis velocity changes by v Δu_j with a triangular acceleration
// (the least jerk for that change): its deviation from the corner is δ Δu_j / 6, so δ = 6 ε_j / Δu_j,
// and its peak acceleration and jerk are v² Δu_j / δ and v³ Δu_j / δ².
//   Blend: each corner on its own: v ≤ √(A_j δ / Δu_j) and ∛(J_j δ² / Δu_j).
//   Smooth: consecutive blends join into one curve of joint curvature κ_j = Δu_j / (2δ): the
//   acceleration v² κ_j is continuous across corners, and the jerk comes from the change of κ_j to the
//   neighbouring corner's over the distance between their middles: v ≤ √(A_j / κ_j), ∛(J_j / ρ_j).
// A velocity jump the axis absorbs within one interpolation cycle (A_j T_ipo) always passes.
struct Corner {
  bool stop = false;   // the tool stops here
  double half = 0;     // δ: the blend's half-length (all axes together)
  Joints axis_half = Joints::Zero();  // each axis's own δ (smooth mode: each axis's curve is smoothed on its own)
  std::array<bool, kMaxJoints> tolerance_bound{};  // the axis's δ is set by its tolerance, not by the blocks' lengths
  double before = 0, after = 0;  // the lengths of the blocks on either side
  Joints jump = Joints::Zero();  // Δu per joint
};

Corner corner_between(const MachineBlock& a, const BlockPath& pa, const MachineBlock& b, const BlockPath& pb, const Machine& m) {
  Corner c;
  c.stop = b.stop_before || a.type == MoveType::Dwell || b.type == MoveType::Dwell || (a.type == MoveType::Rapid) != (b.type == MoveType::Rapid) ||
           m.junction == JunctionMode::ExactStop || pa.rotary_only != pb.rotary_only || !(pa.length > 0) || !(pb.length > 0);
  c.before = pa.length;
  c.after = pb.length;
  if (c.stop) return c;
  c.half = 0.5 * std::min(pa.length, pb.length);
  for (int k = 0; k < m.joint_count(); ++k) {
    c.jump[k] = std::abs(pb.rate_start[k] - pa.rate_end[k]);
    if (!(c.jump[k] > 1e-12)) {
      c.jump[k] = 0;
      continue;
    }
    const AxisLimits& ax = m.axes[k];
    const double tol = ax.rotary ? m.junction_tolerance_rotary : (b.blend_tolerance >= 0 ? b.blend_tolerance : m.junction_tolerance);
    const double by_tolerance = 6 * tol / c.jump[k], by_blocks = 0.5 * std::min(pa.length, pb.length);
    c.axis_half[k] = std::min(by_blocks, by_tolerance);
    c.tolerance_bound[k] = by_tolerance < by_blocks;
    c.half = std::min(c.half, c.axis_half[k]);
  }
  return c;
}

// The speed limit at corner k, given its neighbours (for the smooth mode).
double corner_speed(const std::vector<Corner>& corners, std::size_t k, const Machine& m) {
  const Corner& c = corners[k];
  if (c.stop) return 0;
  double v = kInf, v_jump = kInf;
  bool any = false;
  for (int j = 0; j < m.joint_count(); ++j) {
    const double du = c.jump[j];
    if (!(du > 0)) continue;
    any = true;
    const AxisLimits& ax = m.axes[j];
    v_jump = std::min(v_jump, ax.acceleration * m.interpolation_cycle / du);
    if (!(c.half > 0)) {
      v = 0;
      continue;
    }
    if (m.junction == JunctionMode::Smooth) {
      // The curvature's rate of change towards each neighbour: over the block between the two corners
      // when their blends meet, else from zero within this corner's blend.
      const double half = c.axis_half[j], kappa = du / (2 * half);
      double rho = 0;
      for (int side : {-1, 1}) {
        const Corner& o = corners[side < 0 ? k - 1 : k + 1];
        const double between = side < 0 ? c.before : c.after;
        const bool joined = !o.stop && !c.tolerance_bound[j] && !o.tolerance_bound[j];
        const double kappa_o = o.axis_half[j] > 0 ? o.jump[j] / (2 * o.axis_half[j]) : 0.0;
        rho = std::max(rho, joined ? std::abs(kappa - kappa_o) / between : kappa / half);
      }
      v = std::min({v, std::sqrt(ax.acceleration / kappa), std::cbrt(ax.jerk / rho)});
    } else {
      v = std::min({v, std::sqrt(ax.acceleration * c.half / du), std::cbrt(ax.jerk * c.half * c.half / du)});
    }
  }
  return any ? std::max(v, v_jump) : kInf;
}

}  // namespace

FeedPrediction predict_feed(const MachineProgram& program, const Kinematics& kin) {
  const Machine& m = kin.machine();
  FeedPrediction out;
  out.program_ = program;
  const std::size_t n = program.blocks.size();
  out.blocks.resize(n);
  out.paths_.resize(n);
  out.saturated_length.assign(m.joint_count(), {0, 0, 0});
  std::vector<Limits> limits(n);
  std::vector<double> s(n + 1, 0.0);
  for (std::size_t i = 0; i < n; ++i) {
    const MachineBlock& b = program.blocks[i];
    BlockPrediction& bp = out.blocks[i];
    bp.path_limit = {kInf, kInf, kInf};
    out.paths_[i] = block_path(b, kin);
    bp.length = out.paths_[i].length;
    bp.rotary_only = out.paths_[i].rotary_only;
    bp.s_start = s[i];
    s[i + 1] = s[i] + bp.length;
    bp.programmed_duration = b.programmed_duration;
    if (bp.length > 0) limits[i] = block_limits(b, out.paths_[i], bp, m);
    bp.cap = limits[i].cap;
    bp.cap_source = limits[i].cap_source;
    bp.cap_axis = limits[i].cap_axis;
  }

  // Node limits: node k sits between blocks k-1 and k. Zero-length blocks (dwells) stop the tool.
  std::vector<double> node(n + 1, 0.0);
  std::vector<char> anchor(n + 1, 0);
  anchor[0] = anchor[n] = 1;
  std::vector<Corner> corners(n + 1);
  corners[0].stop = corners[n].stop = true;
  for (std::size_t k = 1; k < n; ++k) corners[k] = corner_between(program.blocks[k - 1], out.paths_[k - 1], program.blocks[k], out.paths_[k], m);
  for (std::size_t k = 1; k < n; ++k) {
    node[k] = std::min({corner_speed(corners, k, m), limits[k - 1].cap, limits[k].cap});
    if (node[k] < std::min(limits[k - 1].cap, limits[k].cap) * (1 - 1e-12)) anchor[k] = 1;
  }
  for (std::size_t k = 0; k < n; ++k) out.blocks[k].end_speed_limit = node[k + 1];

  // Blocks running alone at their own cap, because a stretch through them would exceed it.
  std::vector<char> alone(n, 0);
  std::vector<double> speed(n + 1, 0.0);
  struct Span {
    std::size_t a, b;  // nodes
    MotionLimits lim;
  };
  std::vector<Span> spans;
  for (int iteration = 1;; ++iteration) {
    out.iterations = iteration;
    spans.clear();
    for (std::size_t k = 0, a = 0; k < n; ++k) {
      if (!anchor[k + 1]) continue;
      Span sp{a, k + 1, {0, kInf, kInf}};
      for (std::size_t i = a; i <= k; ++i) {
        if (!(out.blocks[i].length > 0)) continue;
        sp.lim.speed = std::max(sp.lim.speed, limits[i].cap);
        sp.lim.acceleration = std::min(sp.lim.acceleration, limits[i].acceleration);
        sp.lim.jerk = std::min(sp.lim.jerk, limits[i].jerk);
      }
      spans.push_back(sp);
      a = k + 1;
    }
    // Forward and backward sweeps over the anchors.
    std::vector<double> forward(n + 1), backward(n + 1);
    forward[0] = node[0];
    for (const Span& sp : spans) {
      const double d = s[sp.b] - s[sp.a];
      forward[sp.b] = d > 0 && std::isfinite(sp.lim.acceleration)
                          ? std::min(node[sp.b], reachable_speed(forward[sp.a], d, sp.lim.speed, sp.lim.acceleration, sp.lim.jerk))
                          : std::min(node[sp.b], forward[sp.a]);
    }
    backward[n] = node[n];
    for (auto it = spans.rbegin(); it != spans.rend(); ++it) {
      const double d = s[it->b] - s[it->a];
      backward[it->a] = d > 0 && std::isfinite(it->lim.acceleration)
                            ? std::min(node[it->a], reachable_speed(backward[it->b], d, it->lim.speed, it->lim.acceleration, it->lim.jerk))
                            : std::min(node[it->a], backward[it->b]);
    }
    for (const Span& sp : spans) speed[sp.a] = std::min(forward[sp.a], backward[sp.a]);
    speed[n] = std::min(forward[n], backward[n]);

    // One double S per span; blocks whose cap it exceeds run alone next time.
    out.stretches.clear();
    double t = 0;
    bool split = false;
    for (const Span& sp : spans) {
      FeedPrediction::Stretch st;
      st.s0 = s[sp.a];
      st.t0 = t;
      st.first_block = sp.a;
      st.last_block = sp.b - 1;
      const double d = s[sp.b] - s[sp.a];
      if (d > 0 && std::isfinite(sp.lim.acceleration)) {
        st.profile = plan_double_s(speed[sp.a], speed[sp.b], d, sp.lim);
      } else {
        st.profile = DoubleS{};
        st.profile.length = 0;
      }
      t += st.profile.duration();
      if (sp.b - sp.a > 1) {
        // The worst block of the span: the largest overshoot of its cap.
        double worst = 1 + 1e-9;
        std::size_t worst_block = n;
        for (std::size_t i = sp.a; i < sp.b; ++i) {
          if (!(out.blocks[i].length > 0) || limits[i].cap >= st.profile.v_peak * (1 - 1e-12)) continue;
          // The profile rises to its peak then falls: its highest speed on [s_i, s_i+1] is at an end, or the peak.
          const double t0 = st.profile.time_at(s[i] - st.s0), t1 = st.profile.time_at(s[i + 1] - st.s0);
          const double rise_end = st.profile.phases[0].duration + st.profile.phases[1].duration + st.profile.phases[2].duration;
          const double fall_start = rise_end + st.profile.phases[3].duration;
          double v = std::max(st.profile.at(t0).v, st.profile.at(t1).v);
          if (t0 <= fall_start && t1 >= rise_end) v = st.profile.v_peak;
          const double ratio = v / limits[i].cap;
          if (ratio > worst) worst = ratio, worst_block = i;
        }
        if (worst_block < n) {
          alone[worst_block] = 1;
          anchor[worst_block] = anchor[worst_block + 1] = 1;
          node[worst_block] = std::min(node[worst_block], limits[worst_block].cap);
          node[worst_block + 1] = std::min(node[worst_block + 1], limits[worst_block].cap);
          split = true;
        }
      }
      out.stretches.push_back(st);
    }
    if (!split) break;
  }
  out.anchors = static_cast<int>(std::count(anchor.begin(), anchor.end(), 1));
  out.cycle_time = out.stretches.empty() ? 0 : out.stretches.back().t0 + out.stretches.back().profile.duration();

  // Dwells add their time at the node where they stand.
  // (They are zero-length blocks: the stretches pass them at rest.)
  std::vector<double> dwell_before(n + 1, 0.0);
  double extra = 0;
  for (std::size_t i = 0; i < n; ++i) {
    if (program.blocks[i].type == MoveType::Dwell) extra += program.blocks[i].programmed_duration;
    dwell_before[i + 1] = extra;
  }
  for (auto& st : out.stretches) st.t0 += dwell_before[st.first_block];
  out.cycle_time += extra;

  // Per block: times, speeds, and how its length was spent, from the overlap of the block with the
  // phases of its stretch (jerk phases 0, 2, 4, 6; constant acceleration 1, 5; cruise 3).
  std::vector<double> block_start(n, 0.0), block_end(n, 0.0);  // s, predicted; a dwell starts when the tool arrives
  for (const auto& st : out.stretches) {
    double a_lim = kInf, j_lim = kInf;
    int a_axis = -1, j_axis = -1;
    for (std::size_t k = st.first_block; k <= st.last_block; ++k) {
      if (!(out.blocks[k].length > 0)) continue;
      if (limits[k].acceleration < a_lim) a_lim = limits[k].acceleration, a_axis = limits[k].acceleration_axis;
      if (limits[k].jerk < j_lim) j_lim = limits[k].jerk, j_axis = limits[k].jerk_axis;
    }
    // The phases' ends along s.
    std::array<double, 8> phase_s{};
    {
      double t = 0;
      for (int q = 0; q < 7; ++q) {
        t += st.profile.phases[q].duration;
        phase_s[q + 1] = st.profile.at(t).s;
      }
      phase_s[7] = st.profile.length;
    }
    double t_local = 0;
    for (std::size_t i = st.first_block; i <= st.last_block; ++i) {
      BlockPrediction& bp = out.blocks[i];
      const MachineBlock& b = program.blocks[i];
      const double lo = s[i] - st.s0, hi = s[i + 1] - st.s0;
      block_start[i] = st.t0 + t_local;
      if (hi > lo) t_local = st.profile.time_at(hi);
      block_end[i] = st.t0 + t_local;
      if (!(bp.length > 0)) continue;
      std::array<double, 7> overlap{};
      for (int q = 0; q < 7; ++q) overlap[q] = std::max(0.0, std::min(hi, phase_s[q + 1]) - std::max(lo, phase_s[q]));
      const double v0 = st.profile.at(block_start[i] - st.t0).v, v1 = st.profile.at(block_end[i] - st.t0).v;
      bp.min_speed = std::min(v0, v1);
      bp.max_speed = overlap[3] > 0 || (lo <= phase_s[3] && hi >= phase_s[3]) ? st.profile.v_peak : std::max(v0, v1);
      const Limits& l = limits[i];
      const double cruise = overlap[3] * (st.profile.v_peak >= l.cap * (1 - 1e-6) ? 1 : 0);
      const double accelerating = overlap[1] + overlap[5];
      const double jerk = overlap[0] + overlap[2] + overlap[4] + overlap[6];
      bp.length_at_cap = cruise;
      bp.length_accelerating = accelerating * (std::isfinite(a_lim) ? 1 : 0);
      bp.length_in_jerk = jerk;
      const bool cutting = b.type != MoveType::Rapid;
      if (cruise >= std::max(accelerating, jerk) && cruise > 0) bp.limit = l.cap_source, bp.limit_axis = l.cap_axis;
      else if (accelerating >= jerk && accelerating > 0) bp.limit = FeedLimit::AxisAcceleration, bp.limit_axis = a_axis;
      else if (jerk > 0) bp.limit = FeedLimit::AxisJerk, bp.limit_axis = j_axis;
      if (cutting && !bp.rotary_only) {
        out.cutting_length += bp.length;
        if (l.cap_source == FeedLimit::ProgrammedFeed) out.length_at_programmed_feed += cruise;
        if (l.cap_axis >= 0) out.saturated_length[l.cap_axis][l.cap_source == FeedLimit::AxisVelocity ? 0 : l.cap_source == FeedLimit::AxisAcceleration ? 1 : 2] += cruise;
        if (a_axis >= 0) out.saturated_length[a_axis][1] += accelerating;
        if (j_axis >= 0) out.saturated_length[j_axis][2] += jerk;
      }
    }
  }
  for (std::size_t i = 0; i < n; ++i) {
    BlockPrediction& bp = out.blocks[i];
    const MachineBlock& b = program.blocks[i];
    if (b.type == MoveType::Dwell) {
      bp.t_start = i > 0 ? out.blocks[i - 1].t_start + out.blocks[i - 1].duration : 0;
      bp.duration = b.programmed_duration;
    } else {
      bp.t_start = block_start[i];
      bp.duration = block_end[i] - block_start[i];
    }
    out.programmed_time += b.type != MoveType::Rapid && b.programmed_duration > 0 ? b.programmed_duration : bp.duration;
  }
  return out;
}

PathState FeedPrediction::at_time(double t) const {
  PathState st;
  st.t = t;
  if (stretches.empty()) return st;
  auto it = std::upper_bound(stretches.begin(), stretches.end(), t, [](double x, const Stretch& z) { return x < z.t0; });
  const Stretch& z = it == stretches.begin() ? stretches.front() : *(it - 1);
  const double local = std::clamp(t - z.t0, 0.0, z.profile.duration());
  const DoubleS::State d = z.profile.at(local);
  st.s = z.s0 + d.s;
  st.v = d.v;
  st.a = d.a;
  st.j = d.j;
  // The block holding s: the last of the stretch's blocks starting at or before it.
  const auto first = blocks.begin() + static_cast<std::ptrdiff_t>(z.first_block), last = blocks.begin() + static_cast<std::ptrdiff_t>(z.last_block) + 1;
  auto b = std::upper_bound(first, last, st.s, [](double x, const BlockPrediction& p) { return x < p.s_start; });
  st.block = static_cast<std::size_t>((b == first ? first : b - 1) - blocks.begin());
  return st;
}

double FeedPrediction::time_at(double s) const {
  if (stretches.empty()) return 0;
  // The first time the tool is at s: the stretch that reaches it (before any dwell there).
  auto it = std::lower_bound(stretches.begin(), stretches.end(), s, [](const Stretch& z, double x) { return z.s0 < x; });
  const Stretch& z = it == stretches.begin() ? stretches.front() : *(it - 1);
  return z.t0 + z.profile.time_at(s - z.s0);
}

JointState FeedPrediction::joints_at(const PathState& st) const {
  JointState j;
  if (blocks.empty()) return j;
  const std::size_t i = std::min(st.block, blocks.size() - 1);
  const MachineBlock& b = program_.blocks[i];
  const BlockPath& p = paths_[i];
  const double sigma = p.length > 0 ? std::clamp((st.s - blocks[i].s_start) / p.length, 0.0, 1.0) : 0.0;
  const BlockPath::Derivatives d = p.at(b, sigma);
  j.position = d.q;
  j.velocity = d.d1 * st.v;
  j.acceleration = d.d2 * st.v * st.v + d.d1 * st.a;
  j.jerk = d.d3 * st.v * st.v * st.v + 3 * d.d2 * st.v * st.a + d.d1 * st.j;
  return j;
}

}  // namespace drom::machine
