#include "online/loop_simulation.hpp"

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

void SyncError::add(double time_error, double shift) {
  ++samples;
  max_time = std::max(max_time, std::abs(time_error));
  max_shift = std::max(max_shift, shift);
  rms_shift += shift * shift;
}

void SyncError::finish() { rms_shift = samples > 0 ? std::sqrt(rms_shift / static_cast<double>(samples)) : 0.0; }

LoopSimulation::LoopSimulation(const reduce::LightModel& model, PredictorSettings predictor, LoopSimulationSettings settings)
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

LoopMachine::LoopMachine(const reduce::LightModel& model, const TruePart& truth, LoopSimulationSettings settings)
    : model_(model), truth_(truth), settings_(std::move(settings)), passes_(floor_passes(model)), rng_(settings_.seed) {
  if (!(settings_.period > 0) || !(settings_.refresh_rate > 0) || !(settings_.feed_override > 0) || !(settings_.desync >= 0))
    throw std::invalid_argument("closed loop: period, refresh rate and feed override must be > 0, desync >= 0");
  if (!truth.target || truth.final_displacement.cols() != model.shape_nodes.cols())
    throw std::invalid_argument("closed loop: the truth must give the target's history and the final shape at the model's shape nodes");
  sync_ = settings_.sync;
  if (sync_.empty())
    for (Eigen::Index i = 0; i < model.path.rows(); ++i) sync_.push_back(static_cast<int>(i));
  reckoning_ = std::make_unique<DeadReckoning>(model.path, sync_, settings_.reckoning_motion);
  programmed_reckoning_ = std::make_unique<DeadReckoning>(model.path, sync_);
  floor_ = std::make_unique<MachinedFloor>(model);
  // One step is the shorter of the two periods; the longer is a whole number of steps.
  const double refresh = 1 / settings_.refresh_rate;
  step_ = std::min(settings_.period, refresh);
  scan_every_ = std::max(1L, std::lround(settings_.period / step_));
  refresh_every_ = std::max(1L, std::lround(refresh / step_));
  const double program_end = model.path(model.path.rows() - 1, 3);
  steps_ = static_cast<long>(std::ceil(clock_at(program_end) / step_)) + 1;
  calibrating_ = settings_.errors.offset_error.head<2>().norm() > 0 || settings_.errors.angle_error_deg != 0;
}

double LoopMachine::clock_at(double program_time) const {
  if (settings_.machine_motion) return settings_.machine_motion->real_time(program_time);
  return program_time / settings_.feed_override;
}

double LoopMachine::program_time_at(double clock) const {
  if (settings_.machine_motion) return settings_.machine_motion->program_time(clock);
  return std::min(model_.path(model_.path.rows() - 1, 3), clock * settings_.feed_override);
}

LoopMachine::Step LoopMachine::advance(long k) {
  Step s;
  s.index = k;
  s.clock = static_cast<double>(k) * step_;
  s.true_time = program_time_at(s.clock);
  while (next_edge_ < sync_.size() && clock_at(model_.path(sync_[next_edge_], 3)) + settings_.desync <= s.clock) {
    const double at = clock_at(model_.path(sync_[next_edge_], 3)) + settings_.desync;
    reckoning_->edge(sync_[next_edge_], at);
    programmed_reckoning_->edge(sync_[next_edge_], at);
    ++next_edge_;
  }
  s.tip = path_position(model_.path, s.true_time);
  s.believed_time = reckoning_->program_time(s.clock);
  s.programmed_feed_time = programmed_reckoning_->program_time(s.clock);
  s.believed_tip = reckoning_->position_at_program_time(s.believed_time);
  s.pass = pass_of(passes_, s.true_time);

  // The contact point's altitude error against the target surface where it truly is.
  const reduce::SurfaceMesh& target = model_.target;
  const bool ball = model_.tool_shape == reduce::ToolShape::Ball;
  if (s.pass > 0) {
    if (const auto p = target.locate(s.tip.x(), s.tip.y(), -1, ball)) {
      const Eigen::VectorXd& w_now = truth_.target->nodal(s.true_time);
      const double w = target.interpolate(*p, w_now)[0];
      double required = w;  // the offset that would put the tool on the true target surface
      if (ball) {
        double wx = 0, wy = 0, sx = 0, sy = 0;
        for (int n = 0; n < p->count; ++n) {
          const auto i = static_cast<std::size_t>(n);
          wx += p->dx[i] * w_now[p->nodes[i]], wy += p->dy[i] * w_now[p->nodes[i]];
          sx += p->dx[i] * target.nodes()(2, p->nodes[i]), sy += p->dy[i] * target.nodes()(2, p->nodes[i]);
        }
        required += model_.tool_radius * (std::sqrt(1 + (sx + wx) * (sx + wx) + (sy + wy) * (sy + wy)) - std::sqrt(1 + sx * sx + sy * sy));
      }
      s.on_target = true;
      s.sample.clock = s.clock, s.sample.program_time = s.true_time, s.sample.x = s.tip.x(), s.sample.y = s.tip.y();
      s.sample.offset = applied_, s.sample.distortion = w;
      s.sample.error = applied_ - required;  // against the ideal path: the program moved with the true target surface
      s.sample.pass = s.pass;
    }
  }
  s.refresh = k % refresh_every_ == 0;
  s.setpoint_time = s.believed_time + 0.5 / settings_.refresh_rate * settings_.feed_override;
  s.scan = k % scan_every_ == 0;
  current_ = s;
  return s;
}

void LoopMachine::command(double offset) {
  applied_ = offset;
  floor_->command(current_.true_time, offset);
}

std::vector<MeasuredPoint> LoopMachine::scan() {
  const reduce::SurfaceMesh& target = model_.target;
  const double t_true = current_.true_time;
  int hint = -1, top_hint = -1;
  const HeightField read = [&](double x, double y) { return true_height(truth_, target, *floor_, x, y, t_true, hint, top_hint); };
  auto points = online::scan(settings_.sheet, settings_.errors, current_.believed_tip, current_.tip, read, rng_);
  if (calibrating_ && profiles_ % 10 == 0) {
    // What a calibration error does to the surface the predictor fits as the floor (seed §2.3.2):
    // noise-free floor heights where the sheet truly is and where it is believed to be.
    const HeightField read_floor = [&](double x, double y) -> std::optional<double> {
      const auto p = target.locate(x, y, hint, false);
      if (!p) return std::nullopt;
      hint = p->face;
      return floor_->surface(x, y, *p, *truth_.target, t_true);
    };
    LaserSheet actual = settings_.sheet;
    actual.offset += settings_.errors.offset_error;
    actual.angle_deg += settings_.errors.angle_error_deg;
    const auto where = actual.footprint(current_.tip), thought = settings_.sheet.footprint(current_.believed_tip);
    for (std::size_t i = 0; i < where.size(); ++i) {
      const Eigen::Vector2d d = where[i] - thought[i];
      if (d.norm() < 1e-9) continue;
      const Eigen::Vector2d u = d.normalized() * 0.5;
      const auto a = read_floor(where[i].x(), where[i].y()), b = read_floor(thought[i].x(), thought[i].y());
      const auto b_plus = read_floor(thought[i].x() + u.x(), thought[i].y() + u.y()), b_minus = read_floor(thought[i].x() - u.x(), thought[i].y() - u.y());
      if (!a || !b || !b_plus || !b_minus) continue;
      const double bias = *a - *b, expected = (*b_plus - *b_minus) / 1.0 * d.norm();
      sum_be_ += bias * expected, sum_ee_ += expected * expected, sum_bb_ += bias * bias;
      ++calibration_points_;
    }
  }
  ++profiles_;
  return points;
}

CalibrationBias LoopMachine::calibration() const {
  CalibrationBias c;
  c.points = calibration_points_;
  if (calibration_points_ > 0) {
    const auto n = static_cast<double>(calibration_points_);
    c.rms_bias = std::sqrt(sum_bb_ / n);
    c.rms_slope_times_offset = std::sqrt(sum_ee_ / n);
    c.ratio = sum_ee_ > 0 ? sum_be_ / sum_ee_ : 0;
  }
  return c;
}

namespace {

// One figure record per pass, before any step.
LoopSimulationResult result_per_pass(const std::vector<Pass>& passes) {
  LoopSimulationResult result;
  result.passes.resize(passes.size());
  for (std::size_t p = 0; p < passes.size(); ++p) {
    result.passes[p].pass = static_cast<int>(p) + 1;
    result.passes[p].start = passes[p].start;
    result.passes[p].end = passes[p].end;
  }
  return result;
}

// 1. The cut, and its error against the target where it truly is; where the synchronizer thinks it is.
void record_cut(const LoopMachine::Step& step, const Eigen::MatrixXd& path, const Predictor& predictor, LoopSimulationResult& result) {
  if (step.pass > 0) {
    result.sync.add(step.believed_time - step.true_time, (step.believed_tip - step.tip).norm());
    result.sync_programmed_feed.add(step.programmed_feed_time - step.true_time, (path_position(path, step.programmed_feed_time) - step.tip).norm());
  }
  if (step.on_target) {
    LoopSample s = step.sample;
    s.offset_sd = predictor.predicted_offset_sd(step.true_time);
    s.learned = result.learned_at >= 0;
    result.samples.push_back(s);
    auto& f = result.passes[static_cast<std::size_t>(step.pass - 1)];
    ++f.samples;
    f.mean_abs_error += std::abs(s.error);
    f.max_abs_error = std::max(f.max_abs_error, std::abs(s.error));
    f.max_abs_distortion = std::max(f.max_abs_distortion, std::abs(s.distortion));
  }
}

// 2. A new setpoint, for the middle of the interval it will hold (0 when the loop does not correct).
void command_setpoint(const LoopMachine::Step& step, bool correct, LoopMachine& machine, Predictor& predictor, LoopSimulationResult& result) {
  const double applied = correct ? predictor.tool_offset(step.setpoint_time) : 0.0;
  machine.command(applied);
  predictor.record_offset(step.believed_time, applied);
  result.offsets.push_back({step.clock, step.believed_time, step.true_time, applied});
}

// 3. A profile, read where the sheet truly is and handed to the predictor where it is believed to be.
void take_profile(const LoopMachine::Step& step, LoopMachine& machine, Predictor& predictor, LoopSimulationResult& result) {
  const auto points = machine.scan();
  ToolPose pose;
  pose.tip = step.believed_tip;
  pose.applied_offset = machine.applied();
  const ProfileReport report = predictor.add_profile(step.believed_time, pose, points);
  ++result.profiles;
  result.points.used += report.used, result.points.used_top += report.used_top, result.points.outside += report.outside, result.points.not_yet_cut += report.not_yet_cut;
  result.points.invalid += report.invalid, result.points.out_of_range += report.out_of_range;
  if (step.pass > 0) {
    auto& f = result.passes[static_cast<std::size_t>(step.pass - 1)];
    ++f.profiles;
    f.points_used += report.used;
  }
  if (result.learned_at < 0 && predictor.learned()) result.learned_at = step.true_time;
}

// 4. At pass `pass`'s end (0-based): the final shape predicted now, against the truth's.
void compare_final_shape(std::size_t pass, const Predictor& predictor, const TruePart& truth, LoopSimulationResult& result) {
  FinalShape shape = predictor.final_shape();
  result.estimates.push_back(predictor.estimate());
  auto& f = result.passes[pass];
  const Eigen::ArrayXd e = (shape.displacement.row(2) - truth.final_displacement.row(2)).transpose().array().abs();
  f.shape_max_error = e.maxCoeff();
  f.shape_rms_error = std::sqrt(e.square().mean());
  f.shape_band_coverage = (e <= 1.96 * shape.sd.row(2).transpose().array()).cast<double>().mean();
  f.learned = result.learned_at >= 0;
  if (f.samples > 0) f.mean_abs_error /= f.samples;
  result.shapes.push_back(std::move(shape));
}

// The run's totals, once the program has ended.
void close_result(const LoopMachine& machine, const Predictor& predictor, LoopSimulationResult& result) {
  result.calibration = machine.calibration();
  result.rejections = predictor.rejections();
  result.offset_bound = predictor.max_offset();
  result.sync.finish();
  result.sync_programmed_feed.finish();
  result.estimate = predictor.estimate();
}

}  // namespace

LoopSimulationResult LoopSimulation::run(const TruePart& truth, const std::function<void(double)>& progress) const {
  const auto start = std::chrono::steady_clock::now();
  LoopMachine machine(model_, truth, settings_);
  Predictor predictor(model_, predictor_settings_);
  LoopSimulationResult result = result_per_pass(passes_);
  std::size_t next_shape = 0;
  const long steps = machine.steps();
  for (long k = 0; k <= steps; ++k) {
    const LoopMachine::Step step = machine.advance(k);
    record_cut(step, model_.path, predictor, result);
    if (step.refresh) command_setpoint(step, settings_.correct, machine, predictor, result);
    if (step.scan) take_profile(step, machine, predictor, result);
    for (; next_shape < passes_.size() && (step.true_time >= passes_[next_shape].end || k == steps); ++next_shape)
      compare_final_shape(next_shape, predictor, truth, result);
    if (progress && k % std::max(1L, steps / 100) == 0) progress(static_cast<double>(k) / static_cast<double>(steps));
  }
  close_result(machine, predictor, result);
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return result;
}

}  // namespace drom::online
