#include "paths/orient/axis_dynamics.hpp"

#include <Eigen/Geometry>
#include <arkode/arkode_erkstep.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

namespace drom::paths {

double RecallParameters::omega0() const { return 2 * std::numbers::pi * (feed / 60) / spacing; }
double RecallParameters::inertia() const { return stiffness / (omega0() * omega0()); }
double RecallParameters::damping() const { return 2 * damping_ratio * std::sqrt(stiffness * inertia()); }

const char* moment_model_name(MomentModel m) {
  switch (m) {
    case MomentModel::PointG: return "G (3.1)";
    case MomentModel::Lever: return "lever (3.18)";
    case MomentModel::Direction: return "direction (3.19)";
  }
  return "?";
}

FramedPath FramedPath::from_points(const std::vector<Eigen::Vector3d>& cl, const std::vector<Eigen::Vector3d>& normals, double roll, double pitch) {
  if (cl.size() < 2 || normals.size() != cl.size()) throw std::invalid_argument("a framed path needs at least two CL points, each with a normal");
  FramedPath p;
  p.cl = cl;
  p.s.assign(cl.size(), 0);
  for (std::size_t i = 1; i < cl.size(); ++i) {
    const double ds = (cl[i] - cl[i - 1]).norm();
    if (!(ds > 0)) throw std::invalid_argument("CL point " + std::to_string(i) + " repeats the previous one");
    p.s[i] = p.s[i - 1] + ds;
  }
  for (std::size_t i = 0; i < cl.size(); ++i) {
    const std::size_t a = i == 0 ? 0 : i - 1, b = i + 1 == cl.size() ? i : i + 1;
    Eigen::Vector3d f = (cl[b] - cl[a]).normalized();
    Eigen::Vector3d n = normals[i] - normals[i].dot(f) * f;
    if (n.norm() < 1e-9) throw std::invalid_argument("the surface normal lies along the feed at CL point " + std::to_string(i));
    p.feed.push_back(f);
    p.normal.push_back(n.normalized());
  }
  p.roll_prog.assign(cl.size(), roll);
  p.pitch_prog.assign(cl.size(), pitch);
  return p;
}

FramedPath::Frame FramedPath::at(double arc) const {
  arc = std::clamp(arc, 0.0, s.back());
  std::size_t k = static_cast<std::size_t>(std::upper_bound(s.begin(), s.end(), arc) - s.begin());
  k = std::clamp<std::size_t>(k, 1, s.size() - 1);
  const double ds = s[k] - s[k - 1], w = (arc - s[k - 1]) / ds;
  Frame fr;
  fr.cl = cl[k - 1] + w * (cl[k] - cl[k - 1]);
  fr.f = ((1 - w) * feed[k - 1] + w * feed[k]).normalized();
  const Eigen::Vector3d n = (1 - w) * normal[k - 1] + w * normal[k];
  fr.n = (n - n.dot(fr.f) * fr.f).normalized();
  fr.t = fr.f.cross(fr.n);
  fr.roll_prog = (1 - w) * roll_prog[k - 1] + w * roll_prog[k];
  fr.pitch_prog = (1 - w) * pitch_prog[k - 1] + w * pitch_prog[k];
  fr.roll_rate_prog = (roll_prog[k] - roll_prog[k - 1]) / ds;
  fr.pitch_rate_prog = (pitch_prog[k] - pitch_prog[k - 1]) / ds;
  return fr;
}

Eigen::Matrix3d tool_rotation(const FramedPath::Frame& frame, double roll, double pitch) {
  Eigen::Matrix3d base;
  base << frame.f, frame.t, frame.n;
  return (Eigen::AngleAxisd(pitch, frame.t) * Eigen::AngleAxisd(roll, frame.f)).toRotationMatrix() * base;
}

Eigen::Vector3d reference_point(const FramedPath::Frame& frame, const Eigen::Vector3d& axis, double contact_offset) {
  if (contact_offset == 0) return frame.cl;
  // |radial| = sin of the tilt from the normal. Along the normal the flat bottom touches anywhere, and
  // the contact point on the rim jumps across the disc as the axis crosses the normal (why torus
  // programs keep a lead). Within 1° of the normal the reference point slides through the contact
  // instead, so the motion stays continuous for the integrator; the gouge check measures what that
  // costs (at most (R − r) sin 1° of dip, 0.05 mm for R5 r2, and only there).
  const Eigen::Vector3d radial = frame.n - frame.n.dot(axis) * axis;
  constexpr double kSlide = 0.0174524064372835;  // sin 1°
  return frame.cl + contact_offset * radial / std::max(radial.norm(), kSlide);
}

namespace {

struct MomentEvaluation {
  Eigen::Vector3d moment = Eigen::Vector3d::Zero();
  int active = 0;
  double nearest = 1e300;
};

class AxisModel {
 public:
  AxisModel(const FramedPath& path, const std::vector<Eigen::Vector3d>& nodes, const ForceField& field, const DynamicsSettings& settings)
      : path_(path), nodes_(nodes), field_(field), settings_(settings), v0_(settings.recall.feed / 60) {
    if (settings.moment != MomentModel::PointG && nodes.empty()) throw std::invalid_argument("the tool has no node");
    for (const auto& p : nodes) mean_lever_ += p.norm() / static_cast<double>(nodes.size());
    for (const auto& p : nodes) max_lever_ = std::max(max_lever_, p.norm());
    if (settings.moment == MomentModel::PointG) max_lever_ = settings.lever_g;
    max_lever_ += settings.contact_offset;  // a torus's body also swings with its reference point
  }
  int size() const { return settings_.jerk_lag > 0 ? 6 : 4; }
  double v0() const { return v0_; }
  double max_lever() const { return max_lever_; }

  // `with_nearest`: also the nearest obstacle distance (the step cap and the outputs need it, the
  // integrator's right-hand sides do not).
  MomentEvaluation moment(const FramedPath::Frame& fr, double roll, double pitch, bool with_nearest) const {
    const Eigen::Matrix3d R = tool_rotation(fr, roll, pitch);
    // The moment is taken about the path's CL (the pivot); a torus's body sits offset from it.
    const Eigen::Vector3d offset = reference_point(fr, R.col(2), settings_.contact_offset) - fr.cl;
    MomentEvaluation e;
    const auto force_at = [&](const Eigen::Vector3d& p) {
      if (!with_nearest) return field_.force(p);
      const FieldSample f = field_.sample(p);
      e.nearest = std::min(e.nearest, f.nearest);
      return f.force;
    };
    if (settings_.moment == MomentModel::PointG) {
      const Eigen::Vector3d lever = offset + R.col(2) * settings_.lever_g;
      const Eigen::Vector3d f = force_at(fr.cl + lever);
      e.moment = lever.cross(f) + singularity_moment(R.col(2), fr);
      e.active = f.squaredNorm() > 0 ? 1 : 0;
      return e;
    }
    for (const auto& p : nodes_) {
      const Eigen::Vector3d lever = offset + R * p;
      const Eigen::Vector3d f = force_at(fr.cl + lever);
      if (f.squaredNorm() == 0) continue;
      ++e.active;
      e.moment += settings_.moment == MomentModel::Lever ? Eigen::Vector3d(lever.cross(f)) : Eigen::Vector3d(lever.normalized().cross(f) * mean_lever_);
    }
    e.moment += singularity_moment(R.col(2), fr);
    return e;
  }

  // The moment that pushes the axis out of the singular cone: k_s (β0 − β) about d × u, continuous at
  // the cone's edge (a quadratic potential in the intrusion).
  Eigen::Vector3d singularity_moment(const Eigen::Vector3d& u, const FramedPath::Frame& fr) const {
    if (!settings_.singular_direction || settings_.singular_cone <= 0) return Eigen::Vector3d::Zero();
    Eigen::Vector3d d = *settings_.singular_direction;
    if (d.dot(u) < 0) d = -d;
    const double beta = std::acos(std::clamp(d.dot(u), -1.0, 1.0));
    if (beta >= settings_.singular_cone) return Eigen::Vector3d::Zero();
    Eigen::Vector3d away = d.cross(u);
    // On the singular direction itself any way out will do: away from the feed's side.
    away = away.norm() > 1e-12 ? Eigen::Vector3d(away.normalized()) : fr.f;
    return settings_.singular_stiffness * settings_.recall.stiffness * (settings_.singular_cone - beta) * away;
  }

  // y = (θf, θt, θ̇f, θ̇t [, M*f, M*t]); time derivatives.
  void rhs(double t, const Eigen::VectorXd& y, Eigen::VectorXd& dy, MomentEvaluation* out = nullptr) const {
    const FramedPath::Frame fr = path_.at(frozen_at_ >= 0 ? frozen_at_ : v0_ * t);
    const MomentEvaluation e = moment(fr, y(0), y(1), out != nullptr);
    if (out) *out = e;
    Eigen::Vector2d m(e.moment.dot(fr.f), e.moment.dot(fr.t));
    if (settings_.roll_only) m(1) = 0;
    const RecallParameters& rp = settings_.recall;
    const double J = rp.inertia(), c = rp.damping(), k = rp.stiffness;
    const Eigen::Vector2d prog(fr.roll_prog, fr.pitch_prog), prog_rate(fr.roll_rate_prog * v0_, fr.pitch_rate_prog * v0_);
    dy.resize(size());
    Eigen::Vector2d drive = m;
    if (settings_.jerk_lag > 0) {
      drive = y.segment<2>(4);
      dy.segment<2>(4) = (m - drive) / settings_.jerk_lag;
    }
    dy.segment<2>(0) = y.segment<2>(2);
    dy.segment<2>(2) = (drive - c * (y.segment<2>(2) - prog_rate) - k * (y.segment<2>(0) - prog)) / J;
  }

 private:
  const FramedPath& path_;
  const std::vector<Eigen::Vector3d>& nodes_;
  const ForceField& field_;
  const DynamicsSettings& settings_;
  double v0_, mean_lever_ = 0, max_lever_ = 0;

 public:
  double frozen_at_ = -1;  // ≥ 0: the frame held at this arc length (settling the start)
};

struct ArkodeData {
  const OdeRhs* f;
  Eigen::VectorXd y, dy;
};

int arkode_rhs(double t, N_Vector y, N_Vector dy, void* user) {
  auto* d = static_cast<ArkodeData*>(user);
  const long n = N_VGetLength(y);
  d->y = Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(y), n);
  (*d->f)(t, d->y, d->dy);
  Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(dy), n) = d->dy;
  return d->dy.allFinite() ? 0 : 1;  // > 0: recoverable, ARKODE retries with a smaller step
}

}  // namespace

std::vector<Eigen::VectorXd> integrate_rk4(const OdeRhs& f, double t0, Eigen::VectorXd y, const std::vector<double>& times, double step) {
  std::vector<Eigen::VectorXd> out;
  Eigen::VectorXd m1, m2, m3, m4;
  double t = t0;
  for (double target : times) {
    while (t < target - 1e-12 * std::max(1.0, std::abs(target))) {
      const double h = std::min(step, target - t);
      f(t, y, m1);
      f(t + h / 2, y + h / 2 * m1, m2);
      f(t + h / 2, y + h / 2 * m2, m3);
      f(t + h, y + h * m3, m4);
      y += h / 6 * (m1 + 2 * m2 + 2 * m3 + m4);
      t += h;
    }
    out.push_back(y);
  }
  return out;
}

std::vector<Eigen::VectorXd> integrate_arkode(const OdeRhs& f, double t0, Eigen::VectorXd y0, const std::vector<double>& times, double rtol,
                                              double atol, const std::function<double(double, const Eigen::VectorXd&)>& max_step,
                                              long* rhs_evaluations, long* steps) {
  SUNContext ctx = nullptr;
  if (SUNContext_Create(nullptr, &ctx) != 0) throw std::runtime_error("SUNDIALS: no context");
  const auto n = static_cast<sunindextype>(y0.size());
  N_Vector y = N_VNew_Serial(n, ctx);
  Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(y), y0.size()) = y0;
  ArkodeData data{&f, y0, y0};
  void* mem = ERKStepCreate(arkode_rhs, t0, y, ctx);
  auto cleanup = [&] {
    ERKStepFree(&mem);
    N_VDestroy(y);
    SUNContext_Free(&ctx);
  };
  ERKStepSetTableNum(mem, ARKODE_DORMAND_PRINCE_7_4_5);
  ERKStepSStolerances(mem, rtol, atol);
  ERKStepSetUserData(mem, &data);
  ERKStepSetMaxNumSteps(mem, 1000000);
  // No stop time: ARKODE steps as its error control allows and interpolates the outputs (its dense
  // output, of the method's order). Stopping at every 0.1 mm output took 2.2 times the right-hand sides
  // on the impeller for the same clearance (3.958 mm either way).
  std::vector<Eigen::VectorXd> out;
  double t = t0;
  for (double target : times) {
    if (target > t) {
      if (max_step) ERKStepSetMaxStep(mem, std::max(1e-9, max_step(t, Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(y), y0.size()))));
      const int flag = ERKStepEvolve(mem, target, y, &t, ARK_NORMAL);
      if (flag < 0) {
        cleanup();
        throw std::runtime_error("ARKODE failed at t = " + std::to_string(t) + " s (flag " + std::to_string(flag) + ")");
      }
    }
    out.emplace_back(Eigen::Map<Eigen::VectorXd>(N_VGetArrayPointer(y), y0.size()));
  }
  long nfe = 0, nst = 0;
  ERKStepGetNumRhsEvals(mem, &nfe);
  ERKStepGetNumSteps(mem, &nst);
  if (rhs_evaluations) *rhs_evaluations = nfe;
  if (steps) *steps = nst;
  cleanup();
  return out;
}

AxisHistory integrate_axis(const FramedPath& path, const std::vector<Eigen::Vector3d>& nodes, const ForceField& field, const DynamicsSettings& settings,
                           const std::optional<Eigen::Vector2d>& start) {
  if (!(settings.recall.stiffness > 0)) throw std::invalid_argument("the recall stiffness k must be positive");
  AxisModel model(path, nodes, field, settings);
  const double v0 = model.v0(), length = path.length();
  const int outputs = std::max(2, static_cast<int>(std::ceil(length / settings.output_step)) + 1);
  std::vector<double> times;
  for (int i = 0; i < outputs; ++i) times.push_back(length * i / (outputs - 1) / v0);
  const FramedPath::Frame first = path.at(0);
  Eigen::VectorXd y0 = Eigen::VectorXd::Zero(model.size());
  y0(0) = start ? (*start)(0) : first.roll_prog;
  y0(1) = start ? (*start)(1) : first.pitch_prog;
  long evaluations = 0, steps = 0;
  if (settings.settle_start) {
    // The start's equilibrium: the pendulum released at s = 0 with the frame held, for 12/ω0 (a critically
    // damped pendulum has settled to 1e-4 of its step by then), so a pass that starts near an obstacle
    // does not start in collision.
    model.frozen_at_ = 0;
    const OdeRhs held = [&](double t, const Eigen::VectorXd& y, Eigen::VectorXd& dy) { model.rhs(t, y, dy); };
    Eigen::VectorXd settled = integrate_arkode(held, 0, y0, {12 / settings.recall.omega0()}, settings.relative_tolerance, settings.absolute_tolerance).back();
    y0 = settled;
    y0.segment<2>(2).setZero();
    model.frozen_at_ = -1;
  }
  const OdeRhs rhs = [&](double t, const Eigen::VectorXd& y, Eigen::VectorXd& dy) {
    ++evaluations;
    model.rhs(t, y, dy);
  };
  std::vector<Eigen::VectorXd> states;
  if (settings.adaptive) {
    // Cap the step so no node moves more than a fraction of its clearance: the node speed is at most the
    // CL's feed plus the angular rate times the longest lever.
    const auto cap = [&](double t, const Eigen::VectorXd& y) {
      MomentEvaluation e;
      Eigen::VectorXd dy;
      model.rhs(t, y, dy, &e);
      const double speed = v0 + y.segment<2>(2).norm() * model.max_lever();
      const double clearance = std::min(e.nearest, 1e6);
      return settings.clearance_fraction * clearance / speed;
    };
    states = integrate_arkode(rhs, 0, y0, times, settings.relative_tolerance, settings.absolute_tolerance, cap, nullptr, &steps);
  } else {
    states = integrate_rk4(rhs, 0, y0, times, settings.rk4_step / v0);
    steps = static_cast<long>(std::ceil(length / settings.rk4_step));
  }
  AxisHistory h;
  h.rhs_evaluations = evaluations;
  h.steps = steps;
  h.samples.resize(states.size());
  for (std::size_t i = 0; i < states.size(); ++i) {
    const Eigen::VectorXd& y = states[i];
    MomentEvaluation e;
    Eigen::VectorXd dy;
    model.rhs(times[i], y, dy, &e);
    AxisSample& a = h.samples[i];
    a.s = times[i] * v0;
    const FramedPath::Frame fr = path.at(a.s);
    a.roll = y(0);
    a.pitch = y(1);
    a.roll_rate = y(2);
    a.pitch_rate = y(3);
    a.roll_acc = dy(2);
    a.pitch_acc = dy(3);
    a.axis = tool_rotation(fr, a.roll, a.pitch).col(2);
    a.programmed_axis = tool_rotation(fr, fr.roll_prog, fr.pitch_prog).col(2);
    a.cl = reference_point(fr, a.axis, settings.contact_offset);
    a.programmed_cl = reference_point(fr, a.programmed_axis, settings.contact_offset);
    a.moment = e.moment;
    a.active_nodes = e.active;
    a.nearest_node_distance = e.nearest;
    if (settings.jerk_lag > 0) {
      // θ⃛ = (Ṁ* − c (θ̈ − θ̈prog) − k (θ̇ − θ̇prog)) / J, with θ̈prog = 0 on a piecewise-linear program.
      const RecallParameters& rp = settings.recall;
      const Eigen::Vector2d prog_rate(fr.roll_rate_prog * v0, fr.pitch_rate_prog * v0);
      const Eigen::Vector2d jerk = (dy.segment<2>(4) - rp.damping() * dy.segment<2>(2) - rp.stiffness * (y.segment<2>(2) - prog_rate)) / rp.inertia();
      a.roll_jerk = jerk(0);
      a.pitch_jerk = jerk(1);
    }
  }
  if (settings.jerk_lag <= 0)
    for (std::size_t i = 0; i < h.samples.size(); ++i) {
      const std::size_t a = i == 0 ? 0 : i - 1, b = std::min(i + 1, h.samples.size() - 1);
      const double dt = (times[b] - times[a]);
      h.samples[i].roll_jerk = (h.samples[b].roll_acc - h.samples[a].roll_acc) / dt;
      h.samples[i].pitch_jerk = (h.samples[b].pitch_acc - h.samples[a].pitch_acc) / dt;
    }
  return h;
}

void smooth_axis(AxisHistory& history, const FramedPath& path, double sigma, const DynamicsSettings& settings) {
  auto& a = history.samples;
  const std::size_t n = a.size();
  if (n < 3 || sigma <= 0) return;
  const double ds = (a.back().s - a.front().s) / static_cast<double>(n - 1), v0 = settings.recall.feed / 60, dt = ds / v0;
  if (!(ds > 0)) return;
  const int half = static_cast<int>(std::ceil(3 * sigma / ds));
  std::vector<double> weight(static_cast<std::size_t>(half) + 1);
  double total = 0;
  for (int k = 0; k <= half; ++k) total += (k == 0 ? 1 : 2) * (weight[static_cast<std::size_t>(k)] = std::exp(-0.5 * (k * ds / sigma) * (k * ds / sigma)));
  std::vector<FramedPath::Frame> frames(n);
  std::vector<double> roll(n), pitch(n);
  for (std::size_t i = 0; i < n; ++i) {
    frames[i] = path.at(a[i].s);
    roll[i] = a[i].roll - frames[i].roll_prog;
    pitch[i] = a[i].pitch - frames[i].pitch_prog;
  }
  // Odd reflection about the ends: x(−k) = 2 x(0) − x(k), so the end values and slopes stay.
  const auto at = [&](const std::vector<double>& x, long i) {
    const long last = static_cast<long>(n) - 1;
    if (i < 0) return 2 * x.front() - x[static_cast<std::size_t>(std::min(-i, last))];
    if (i > last) return 2 * x.back() - x[static_cast<std::size_t>(std::max(2 * last - i, 0L))];
    return x[static_cast<std::size_t>(i)];
  };
  const auto smooth = [&](const std::vector<double>& x) {
    std::vector<double> y(n);
    for (std::size_t i = 0; i < n; ++i) {
      double sum = 0;
      for (int k = -half; k <= half; ++k) sum += weight[static_cast<std::size_t>(std::abs(k))] * at(x, static_cast<long>(i) + k);
      y[i] = sum / total;
    }
    return y;
  };
  const std::vector<double> r = smooth(roll), p = smooth(pitch);
  const auto derivative = [&](const std::vector<double>& x) {
    std::vector<double> d(n);
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t lo = i == 0 ? 0 : i - 1, hi = std::min(i + 1, n - 1);
      d[i] = (x[hi] - x[lo]) / (static_cast<double>(hi - lo) * dt);
    }
    return d;
  };
  std::vector<double> fr(n), pt(n);
  for (std::size_t i = 0; i < n; ++i) {
    fr[i] = r[i] + frames[i].roll_prog;
    pt[i] = p[i] + frames[i].pitch_prog;
  }
  const auto r1 = derivative(fr), p1 = derivative(pt), r2 = derivative(r1), p2 = derivative(p1), r3 = derivative(r2), p3 = derivative(p2);
  for (std::size_t i = 0; i < n; ++i) {
    AxisSample& s = a[i];
    s.roll = fr[i];
    s.pitch = pt[i];
    s.roll_rate = r1[i];
    s.pitch_rate = p1[i];
    s.roll_acc = r2[i];
    s.pitch_acc = p2[i];
    s.roll_jerk = r3[i];
    s.pitch_jerk = p3[i];
    s.axis = tool_rotation(frames[i], s.roll, s.pitch).col(2);
    s.cl = reference_point(frames[i], s.axis, settings.contact_offset);
  }
}

double free_response(double theta0, double rate0, double omega0, double xi, double t) {
  if (std::abs(xi - 1) < 1e-12) return (theta0 + (rate0 + omega0 * theta0) * t) * std::exp(-omega0 * t);
  if (xi < 1) {
    const double wd = omega0 * std::sqrt(1 - xi * xi);
    return std::exp(-xi * omega0 * t) * (theta0 * std::cos(wd * t) + (rate0 + xi * omega0 * theta0) / wd * std::sin(wd * t));
  }
  const double root = omega0 * std::sqrt(xi * xi - 1), r1 = -xi * omega0 + root, r2 = -xi * omega0 - root;
  const double a = (rate0 - r2 * theta0) / (r1 - r2), b = theta0 - a;
  return a * std::exp(r1 * t) + b * std::exp(r2 * t);
}

}  // namespace drom::paths
