#include "paths/orient/orientation_under_limits.hpp"
#include "paths/cutter/stepover.hpp"

#include "machine/cl_data.hpp"
#include "support/input_error.hpp"

#include <Eigen/Geometry>
#include <nlopt.hpp>

#include <algorithm>
#include <cmath>
#include <limits>

namespace drom::paths {

machine::ClPose tool_pose(const PassPoint& p, const Tool& tool, const Orientation& o) {
  const Eigen::Vector3d n = p.normal.normalized();
  const Eigen::Vector3d f = (p.feed - n * n.dot(p.feed)).normalized();
  const Eigen::Vector3d b = n.cross(f);
  const Eigen::Vector3d d = std::cos(o.yaw) * f + std::sin(o.yaw) * b;
  const Eigen::Vector3d axis = std::cos(o.tilt) * n + std::sin(o.tilt) * d;
  const Eigen::Vector3d v = std::sin(o.tilt) * n - std::cos(o.tilt) * d;
  const Eigen::Vector3d guide = p.contact + tool.corner_radius * n;  // on S1, whatever the orientation
  return {guide + (tool.radius - tool.corner_radius) * v - tool.corner_radius * axis, axis};
}

double effective_radius(const Tool& tool, const Orientation& o) {
  if (!(std::sin(o.tilt) > 1e-12)) return std::numeric_limits<double>::infinity();
  return paths::effective_radius(tool, o.tilt, o.yaw);
}

double pass_time(const SurfacePass& pass, const Tool& tool, const std::vector<Orientation>& orientation, const machine::Kinematics& kin) {
  machine::ClProgram cl;
  cl.origin = "pass";
  for (std::size_t i = 0; i < pass.points.size(); ++i) {
    machine::ClPoint p;
    p.pose = tool_pose(pass.points[i], tool, orientation[i]);
    p.feed = pass.feed;
    p.rapid = i == 0;
    p.line = static_cast<int>(i) + 1;
    cl.points.push_back(p);
  }
  const machine::ClOnMachine on = machine::cl_to_machine_program(cl, kin);
  if (!on.joints.violations.empty()) return std::numeric_limits<double>::infinity();
  return machine::predict_feed(on.program, kin).cycle_time;
}

namespace {

// Uniform cubic B-spline basis on [0, length] with k control values, clamped (the ends interpolate).
Eigen::MatrixXd bspline_basis(const std::vector<double>& s, double length, int k) {
  const int degree = 3, spans = k - degree;
  Eigen::MatrixXd basis = Eigen::MatrixXd::Zero(static_cast<Eigen::Index>(s.size()), k);
  std::vector<double> knots;
  for (int i = 0; i <= degree; ++i) knots.push_back(0);
  for (int i = 1; i < spans; ++i) knots.push_back(length * i / spans);
  for (int i = 0; i <= degree; ++i) knots.push_back(length);
  for (std::size_t row = 0; row < s.size(); ++row) {
    const double x = std::clamp(s[row], 0.0, length);
    // Cox-de Boor on the clamped knot vector.
    std::vector<double> n(knots.size() - 1, 0.0);
    for (std::size_t j = 0; j + 1 < knots.size(); ++j)
      n[j] = (x >= knots[j] && x < knots[j + 1]) || (x == length && knots[j] < length && knots[j + 1] == length) ? 1.0 : 0.0;
    for (int p = 1; p <= degree; ++p)
      for (std::size_t j = 0; j + p + 1 < knots.size(); ++j) {
        const double a = knots[j + p] > knots[j] ? (x - knots[j]) / (knots[j + p] - knots[j]) * n[j] : 0.0;
        const double c = knots[j + p + 1] > knots[j + 1] ? (knots[j + p + 1] - x) / (knots[j + p + 1] - knots[j + 1]) * n[j + 1] : 0.0;
        n[j] = a + c;
      }
    for (int j = 0; j < k; ++j) basis(static_cast<Eigen::Index>(row), j) = n[static_cast<std::size_t>(j)];
  }
  return basis;
}

}  // namespace

PassOrientation relax_orientation(const SurfacePass& pass, const Tool& tool, const std::vector<Orientation>& programmed, const machine::Kinematics& kin,
                                  const RelaxationSettings& settings) {
  const std::size_t n = pass.points.size();
  if (n < 2) throw InputError("orientation relaxation: a pass needs at least two points");
  if (programmed.size() != n) throw std::invalid_argument("relax_orientation: one programmed orientation per point");
  if (!(settings.tilt_min >= 0) || !(settings.tilt_max > settings.tilt_min) || settings.tilt_max >= 1.5)
    throw InputError("orientation relaxation: tilt bounds must satisfy 0 <= min < max < 86 deg");
  const int k = std::max(4, settings.control_points);
  std::vector<double> s(n, 0.0);
  for (std::size_t i = 1; i < n; ++i) s[i] = s[i - 1] + (pass.points[i].contact - pass.points[i - 1].contact).norm();
  const Eigen::MatrixXd basis = bspline_basis(s, s.back(), k);
  const bool yaw = settings.free_yaw;
  // Start from the programmed fields, fitted in the basis and put within the bounds.
  Eigen::VectorXd tilt0(static_cast<Eigen::Index>(n)), yaw0(static_cast<Eigen::Index>(n));
  for (std::size_t i = 0; i < n; ++i) tilt0[static_cast<Eigen::Index>(i)] = programmed[i].tilt, yaw0[static_cast<Eigen::Index>(i)] = programmed[i].yaw;
  const Eigen::VectorXd tilt_fit = basis.colPivHouseholderQr().solve(tilt0), yaw_fit = basis.colPivHouseholderQr().solve(yaw0);
  const int dims = yaw ? 2 * k : k;
  std::vector<double> x(static_cast<std::size_t>(dims)), lower(x.size()), upper(x.size());
  for (int j = 0; j < k; ++j) {
    lower[static_cast<std::size_t>(j)] = settings.tilt_min, upper[static_cast<std::size_t>(j)] = settings.tilt_max;
    x[static_cast<std::size_t>(j)] = std::clamp(tilt_fit[j], settings.tilt_min, settings.tilt_max);
    if (yaw) {
      const auto y = static_cast<std::size_t>(k + j);
      lower[y] = yaw_fit[j] - settings.yaw_range, upper[y] = yaw_fit[j] + settings.yaw_range, x[y] = yaw_fit[j];
    }
  }
  auto fields = [&](const std::vector<double>& v) {
    const Eigen::Map<const Eigen::VectorXd> t(v.data(), k);
    const Eigen::VectorXd tilt = basis * t;
    Eigen::VectorXd y = yaw0;
    if (yaw) y = basis * Eigen::Map<const Eigen::VectorXd>(v.data() + k, k);
    std::vector<Orientation> o(n);
    for (std::size_t i = 0; i < n; ++i) o[i] = {tilt[static_cast<Eigen::Index>(i)], y[static_cast<Eigen::Index>(i)]};
    return o;
  };
  PassOrientation out;
  out.time_before = pass_time(pass, tool, programmed, kin);
  struct Context {
    decltype(fields)* make;
    const SurfacePass* pass;
    const Tool* tool;
    const machine::Kinematics* kin;
    const std::vector<Orientation>* programmed;
    int evaluations = 0;
  } ctx{&fields, &pass, &tool, &kin, &programmed};
  auto objective = [](const std::vector<double>& v, std::vector<double>&, void* data) {
    auto* c = static_cast<Context*>(data);
    ++c->evaluations;
    const auto o = (*c->make)(v);
    double deviation = 0;
    for (std::size_t i = 0; i < o.size(); ++i)
      deviation += std::pow(o[i].tilt - (*c->programmed)[i].tilt, 2) + std::pow(o[i].yaw - (*c->programmed)[i].yaw, 2);
    const double t = pass_time(*c->pass, *c->tool, o, *c->kin);
    return std::isfinite(t) ? t + 1e-3 * deviation / static_cast<double>(o.size()) : 1e9;
  };
  // BOBYQA is local and the time is not convex in the tilt: start it from the best of a few fields
  // a CAM programmer would try. The programmed one; the bounds' middle and top everywhere; and the
  // seed's relief, the top tilt at the pass's slowest point blended into the programmed tilt over an
  // eighth, a quarter or half of the pass (the control values fitted by least squares).
  {
    machine::ClProgram cl;
    for (std::size_t i = 0; i < n; ++i) cl.points.push_back({tool_pose(pass.points[i], tool, programmed[i]), pass.feed, i == 0, 0});
    const machine::ClOnMachine on = machine::cl_to_machine_program(cl, kin);
    double slowest_s = 0.5 * s.back();
    if (on.joints.violations.empty()) {
      const machine::FeedPrediction p = machine::predict_feed(on.program, kin);
      double slowest = std::numeric_limits<double>::infinity();
      for (std::size_t b = 0; b < p.blocks.size(); ++b) {
        const double margin = 0.1 * s.back();  // not the ramps at the pass's ends
        if (s[b + 1] > margin && s[b + 1] < s.back() - margin && p.blocks[b].min_speed < slowest) slowest = p.blocks[b].min_speed, slowest_s = s[b + 1];
      }
    }
    std::vector<std::vector<double>> starts{x};
    auto uniform = [&](double t) {
      std::vector<double> v = x;
      for (int j = 0; j < k; ++j) v[static_cast<std::size_t>(j)] = t;
      return v;
    };
    starts.push_back(uniform(0.5 * (settings.tilt_min + settings.tilt_max)));
    starts.push_back(uniform(settings.tilt_max));
    for (double fraction : {0.125, 0.25, 0.5}) {
      const double radius = fraction * s.back();
      Eigen::VectorXd bump(static_cast<Eigen::Index>(n));
      for (std::size_t i = 0; i < n; ++i) {
        const double d = std::abs(s[i] - slowest_s), w = d < radius ? 0.5 * (1 + std::cos(3.14159265358979323846 * d / radius)) : 0.0;
        bump[static_cast<Eigen::Index>(i)] = tilt0[static_cast<Eigen::Index>(i)] + w * (settings.tilt_max - tilt0[static_cast<Eigen::Index>(i)]);
      }
      const Eigen::VectorXd c = basis.colPivHouseholderQr().solve(bump);
      std::vector<double> v = x;
      for (int j = 0; j < k; ++j) v[static_cast<std::size_t>(j)] = std::clamp(c[j], settings.tilt_min, settings.tilt_max);
      starts.push_back(v);
    }
    std::vector<double> unused_gradient;
    double best_start = std::numeric_limits<double>::infinity();
    for (const auto& v : starts) {
      const double f = objective(v, unused_gradient, &ctx);
      if (f < best_start) best_start = f, x = v;
    }
  }
  nlopt::opt opt(nlopt::LN_BOBYQA, static_cast<unsigned>(dims));
  opt.set_lower_bounds(lower);
  opt.set_upper_bounds(upper);
  opt.set_min_objective(objective, &ctx);
  opt.set_maxeval(settings.max_evaluations);
  opt.set_xtol_abs(1e-4);  // rad: 0.006°
  std::vector<double> step(x.size(), 0.25 * (settings.tilt_max - settings.tilt_min));
  if (yaw)
    for (int j = 0; j < k; ++j) step[static_cast<std::size_t>(k + j)] = 0.25 * settings.yaw_range;
  opt.set_initial_step(step);
  double best = 0;
  try {
    opt.optimize(x, best);
  } catch (const nlopt::roundoff_limited&) {
    // BOBYQA stops where rounding hides any progress: x holds its best point.
  }
  out.evaluations = ctx.evaluations;
  out.orientation = fields(x);
  out.time_after = pass_time(pass, tool, out.orientation, kin);
  if (!std::isfinite(out.time_after)) throw InputError("orientation relaxation: no admissible tilt reaches every pose of the pass on " + kin.machine().name);
  if (out.time_after > out.time_before && std::isfinite(out.time_before)) {  // never worse than what was programmed
    out.orientation = programmed;
    out.time_after = out.time_before;
  }
  for (std::size_t i = 0; i < n; ++i) {
    out.poses.push_back(tool_pose(pass.points[i], tool, out.orientation[i]));
    const double r = effective_radius(tool, out.orientation[i]);
    out.effective_radius.push_back(r);
    out.scallop.push_back(flat_scallop(settings.stepover, r));
    const double kappa = pass.points[i].cross_curvature;
    out.gouge_margin.push_back(kappa > 0 ? 1 / kappa - r : std::numeric_limits<double>::infinity());
  }
  return out;
}

}  // namespace drom::paths
