#include "online/closed_loop.hpp"

#include "online/dead_reckoning.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <random>
#include <stdexcept>

namespace drom::online {

std::vector<Pass> floor_passes(const reduce::LightModel& model) {
  const Eigen::MatrixXd& path = model.path;
  const double tolerance = 0.02 * model.pocket_depth;
  auto on_floor = [&](Eigen::Index i) {
    const auto p = model.target.locate(path(i, 0), path(i, 1), -1, false);
    return p && std::abs(path(i, 2) - model.target.nominal_altitude(*p)) <= tolerance;
  };
  std::vector<Pass> passes;
  bool previous = false;
  for (Eigen::Index i = 0; i + 1 < path.rows(); ++i) {
    const bool floor = on_floor(i) && on_floor(i + 1) && path(i + 1, 3) > path(i, 3);
    if (floor && previous) passes.back().end = path(i + 1, 3);
    else if (floor) passes.push_back({path(i, 3), path(i + 1, 3)});
    previous = floor;
  }
  return passes;
}

ClosedLoop::ClosedLoop(const reduce::LightModel& model, PredictorSettings predictor, ClosedLoopSettings settings)
    : model_(model), predictor_settings_(predictor), settings_(std::move(settings)), passes_(floor_passes(model)) {
  if (!(settings_.period > 0) || !(settings_.refresh_rate > 0) || !(settings_.feed_override > 0) || !(settings_.desync >= 0))
    throw std::invalid_argument("closed loop: period, refresh rate and feed override must be > 0, desync >= 0");
  if (passes_.empty()) throw std::invalid_argument("closed loop: the program never puts the tool on the target surface at its depth");
}

namespace {

int pass_of(const std::vector<Pass>& passes, double t) {
  const auto it = std::upper_bound(passes.begin(), passes.end(), t, [](double v, const Pass& p) { return v < p.end; });
  if (it == passes.end() || t < it->start) return 0;
  return static_cast<int>(it - passes.begin()) + 1;
}

}  // namespace

std::optional<double> true_height(const TruePart& truth, const reduce::SurfaceMesh& target, const MachinedFloor& floor, double x, double y, double t, int& hint,
                                  int& top_hint) {
  const auto p = target.locate(x, y, hint, false);
  if (p) {
    hint = p->face;
    if (const auto z = floor.surface(x, y, *p, *truth.target, t)) return z;
  }
  const auto top = truth.stock_top(x, y);
  if (!top) return std::nullopt;
  if (truth.top)
    if (const auto q = truth.top->mesh().locate(x, y, top_hint, false)) {
      top_hint = q->face;
      if (!p || !truth.top_cut_time || reduce::face_uncut(*q, *truth.top_cut_time, t)) return *top + truth.top->at(*q, t);
    }
  return *top + (p ? truth.target->at(*p, t) : 0.0);
}

ClosedLoopResult ClosedLoop::run(const TruePart& truth, const std::function<void(double)>& progress) const {
  const auto start = std::chrono::steady_clock::now();
  if (!truth.target || truth.final_displacement.cols() != model_.shape_nodes.cols())
    throw std::invalid_argument("closed loop: the truth must give the target's history and the final shape at the model's shape nodes");
  const SurfaceHistory& w_true = *truth.target;
  const reduce::SurfaceMesh& target = model_.target;
  Predictor predictor(model_, predictor_settings_);
  std::vector<int> sync = settings_.sync;
  if (sync.empty())
    for (Eigen::Index i = 0; i < model_.path.rows(); ++i) sync.push_back(static_cast<int>(i));
  DeadReckoning reckoning(model_.path, sync);
  MachinedFloor floor(model_);
  std::mt19937 rng(settings_.seed);

  // One step is the shorter of the two periods; the longer is a whole number of steps.
  const double refresh = 1 / settings_.refresh_rate;
  const double step = std::min(settings_.period, refresh);
  const long scan_every = std::max(1L, std::lround(settings_.period / step)), refresh_every = std::max(1L, std::lround(refresh / step));
  const double program_end = model_.path(model_.path.rows() - 1, 3);
  const double radius = model_.tool_radius;
  const bool ball = model_.tool_shape == reduce::ToolShape::Ball;

  ClosedLoopResult result;
  result.passes.resize(passes_.size());
  for (std::size_t p = 0; p < passes_.size(); ++p) {
    result.passes[p].pass = static_cast<int>(p) + 1;
    result.passes[p].start = passes_[p].start;
    result.passes[p].end = passes_[p].end;
  }
  std::size_t next_edge = 0, next_shape = 0;
  const bool calibrating = settings_.errors.offset_error.head<2>().norm() > 0 || settings_.errors.angle_error_deg != 0;
  double sum_be = 0, sum_ee = 0, sum_bb = 0;
  double applied = 0;
  const long steps = static_cast<long>(std::ceil(program_end / settings_.feed_override / step)) + 1;
  for (long k = 0; k <= steps; ++k) {
    const double clock = static_cast<double>(k) * step, t_true = std::min(program_end, clock * settings_.feed_override);
    while (next_edge < sync.size() && model_.path(sync[next_edge], 3) / settings_.feed_override + settings_.desync <= clock) {
      reckoning.edge(sync[next_edge], model_.path(sync[next_edge], 3) / settings_.feed_override + settings_.desync);
      ++next_edge;
    }
    const Eigen::Vector3d tip = path_position(model_.path, t_true);
    const Eigen::VectorXd& w_now = w_true.nodal(t_true);

    // 1. The cut, and the contact point's altitude error against the target surface where it truly is.
    const int pass = pass_of(passes_, t_true);
    if (pass > 0) {
      if (const auto p = target.locate(tip.x(), tip.y(), -1, ball)) {
        const double w = target.interpolate(*p, w_now)[0];
        double required = w;  // the offset that would put the tool on the true target surface
        if (ball) {
          double wx = 0, wy = 0, sx = 0, sy = 0;
          for (int n = 0; n < p->count; ++n) {
            const auto i = static_cast<std::size_t>(n);
            wx += p->dx[i] * w_now[p->nodes[i]], wy += p->dy[i] * w_now[p->nodes[i]];
            sx += p->dx[i] * target.nodes()(2, p->nodes[i]), sy += p->dy[i] * target.nodes()(2, p->nodes[i]);
          }
          required += radius * (std::sqrt(1 + (sx + wx) * (sx + wx) + (sy + wy) * (sy + wy)) - std::sqrt(1 + sx * sx + sy * sy));
        }
        LoopSample s;
        s.clock = clock, s.program_time = t_true, s.x = tip.x(), s.y = tip.y();
        s.offset = applied, s.distortion = w;
        s.offset_sd = predictor.predicted_offset_sd(t_true);
        s.error = applied - required;  // against the ideal path: the program moved with the true target surface
        s.pass = pass;
        s.learned = result.learned_at >= 0;
        result.samples.push_back(s);
        auto& f = result.passes[static_cast<std::size_t>(pass - 1)];
        ++f.samples;
        f.mean_abs_error += std::abs(s.error);
        f.max_abs_error = std::max(f.max_abs_error, std::abs(s.error));
        f.max_abs_distortion = std::max(f.max_abs_distortion, std::abs(w));
      }
    }

    // 2. A new setpoint, for the middle of the interval it will hold.
    const double t_believed = reckoning.program_time(clock);
    if (k % refresh_every == 0) {
      const double target_time = t_believed + 0.5 * refresh * settings_.feed_override;
      applied = settings_.correct ? predictor.tool_offset(target_time) : 0.0;
      floor.command(t_true, applied);
      predictor.record_offset(t_believed, applied);
      result.offsets.push_back({clock, t_believed, t_true, applied});
    }

    // 3. A profile: readings from where the sheet truly is, placed where the predictor believes.
    if (k % scan_every == 0) {
      int hint = -1, top_hint = -1;
      const HeightField read = [&](double x, double y) { return true_height(truth, target, floor, x, y, t_true, hint, top_hint); };
      const Eigen::Vector3d believed = reckoning.position_at_program_time(t_believed);
      const auto points = scan(settings_.sheet, settings_.errors, believed, tip, read, rng);
      if (calibrating && result.profiles % 10 == 0) {
        // Noise-free floor heights only: the rule is about the surface the predictor fits as the floor.
        const HeightField read_floor = [&](double x, double y) -> std::optional<double> {
          const auto p = target.locate(x, y, hint, false);
          if (!p) return std::nullopt;
          hint = p->face;
          return floor.surface(x, y, *p, w_true, t_true);
        };
        LaserSheet actual = settings_.sheet;
        actual.offset += settings_.errors.offset_error;
        actual.angle_deg += settings_.errors.angle_error_deg;
        const auto where = actual.footprint(tip), thought = settings_.sheet.footprint(believed);
        for (std::size_t i = 0; i < where.size(); ++i) {
          const Eigen::Vector2d d = where[i] - thought[i];
          if (d.norm() < 1e-9) continue;
          const Eigen::Vector2d u = d.normalized() * 0.5;
          const auto a = read_floor(where[i].x(), where[i].y()), b = read_floor(thought[i].x(), thought[i].y());
          const auto b_plus = read_floor(thought[i].x() + u.x(), thought[i].y() + u.y()), b_minus = read_floor(thought[i].x() - u.x(), thought[i].y() - u.y());
          if (!a || !b || !b_plus || !b_minus) continue;
          const double bias = *a - *b, expected = (*b_plus - *b_minus) / 1.0 * d.norm();
          sum_be += bias * expected, sum_ee += expected * expected, sum_bb += bias * bias;
          ++result.calibration.points;
        }
      }
      ToolPose pose;
      pose.tip = believed;
      pose.applied_offset = applied;
      const ProfileReport report = predictor.add_profile(t_believed, pose, points);
      ++result.profiles;
      result.points.used += report.used, result.points.used_top += report.used_top, result.points.outside += report.outside, result.points.not_yet_cut += report.not_yet_cut;
      result.points.invalid += report.invalid, result.points.out_of_range += report.out_of_range;
      if (pass > 0) {
        auto& f = result.passes[static_cast<std::size_t>(pass - 1)];
        ++f.profiles;
        f.points_used += report.used;
      }
      if (result.learned_at < 0 && predictor.learned()) result.learned_at = t_true;
    }

    // 4. At each pass's end: the final shape predicted now, against the truth's.
    while (next_shape < passes_.size() && (t_true >= passes_[next_shape].end || k == steps)) {
      FinalShape shape = predictor.final_shape();
      result.estimates.push_back(predictor.estimate());
      auto& f = result.passes[next_shape];
      const Eigen::ArrayXd e = (shape.displacement.row(2) - truth.final_displacement.row(2)).transpose().array().abs();
      f.shape_max_error = e.maxCoeff();
      f.shape_rms_error = std::sqrt(e.square().mean());
      f.shape_band_coverage = (e <= 1.96 * shape.sd.row(2).transpose().array()).cast<double>().mean();
      f.learned = result.learned_at >= 0;
      if (f.samples > 0) f.mean_abs_error /= f.samples;
      result.shapes.push_back(std::move(shape));
      ++next_shape;
    }
    if (progress && k % std::max(1L, steps / 100) == 0) progress(static_cast<double>(k) / static_cast<double>(steps));
  }
  if (result.calibration.points > 0) {
    const auto n = static_cast<double>(result.calibration.points);
    result.calibration.rms_bias = std::sqrt(sum_bb / n);
    result.calibration.rms_slope_times_offset = std::sqrt(sum_ee / n);
    result.calibration.ratio = sum_ee > 0 ? sum_be / sum_ee : 0;
  }
  result.estimate = predictor.estimate();
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace drom::online
