#include "loop/closed_loop_setup.hpp"

#include "machine/program_clock.hpp"

#include "support/toml_reader.hpp"
#include "offline/part_setup.hpp"
#include "support/atomic_file.hpp"
#include "support/hdf5_eigen.hpp"
#include "offline/offline_job.hpp"
#include "reduce/database_reduction.hpp"
#include "reduce/model_reduction.hpp"
#include "support/file_format.hpp"
#include "support/hdf5_reader.hpp"
#include "support/input_error.hpp"
#include "support/resources.hpp"
#include "support/run_folder.hpp"
#include "support/stop_request.hpp"
#include "support/summary.hpp"

#include <chrono>
#include <exception>
#include <cmath>
#include <iostream>
#include <map>
#include <optional>
#include <thread>
#include <tuple>

namespace drom::loop {

case_file::Case load_run_case(const std::optional<std::filesystem::path>& path, const std::vector<std::string>& overrides) {
  const case_file::Case as_written = case_file::load_case(path, overrides);
  if (as_written.run_scale != "quick" || as_written.run_quick.empty()) return as_written;
  std::vector<std::string> all = as_written.run_quick;
  all.insert(all.end(), overrides.begin(), overrides.end());
  return case_file::load_case(path, all);
}

namespace {

const std::vector<std::string> kLoopTables = {"sensor", "sync", "control", "run", "program"};
const std::vector<std::string> kPathKeys = {"part.stl", "stress.table", "truth.table", "path.gcode"};

// A stage (offline or truth) to compute: its case and options, for `text` in `dir`; none when
// dir/database.h5 already holds it (same case, this drom's format).
struct Stage {
  case_file::Case c;
  offline::JobOptions options;
};

// The stage for `text` in `dir`, as it runs (rank 0 has decided it must, and prepared `dir`).
Stage stage_in(const std::string& text, const std::filesystem::path& dir, const RunOptions& options) {
  Stage stage{case_file::case_from_text(text, (dir / "case.toml").string()), {}};
  stage.options.out = dir;
  stage.options.quiet = options.quiet;
  stage.options.threads = options.threads;
  stage.options.frames = 0;
  stage.options.resume = std::filesystem::exists(dir / ".checkpoint");
  stage.options.team = options.team;
  stage.options.stop = options.stop;
  return stage;
}

std::optional<Stage> stage_to_run(const std::string& text, const std::filesystem::path& dir, const RunOptions& options) {
  const auto case_file = dir / "case.toml";
  const auto database = dir / "database.h5";
  const case_file::Case c = case_file::case_from_text(text, case_file.string());
  if (std::filesystem::exists(database)) {
    bool current = false;
    try {
      const Hdf5Reader db(database);
      check_file_format(db, kSnapshotDatabase);
      current = db.text_attribute("case") == c.resolved_toml;
    } catch (const InputError&) {
      current = false;  // another drom's format: recompute
    }
    if (current) return std::nullopt;
    std::filesystem::remove(database);  // made by another case or format: recompute
  }
  std::filesystem::create_directories(dir);
  write_file_atomically(case_file, text);
  return stage_in(text, dir, options);
}

// Checks a stage wrote its database.
void check_finished(const offline::JobResult& result, const std::filesystem::path& dir, const std::stop_token& stop) {
  if (!result.finished) throw_if_stop_requested(stop);
  if (!result.finished || !std::filesystem::exists(dir / "database.h5"))
    throw InputError(dir.string() + ": the stage stopped before writing database.h5; run again to resume it");
}


// 1. The machining simulations: the offline snapshots of the basis's unit profiles (nothing of the
//    truth or the loop in their case, so changing those reuses them) and the truth, the [truth]
//    profile on the same mesh and program. When both must be computed, one pass serves them: one
//    factorization per station, each database the one its own stage would write. Rank 0 decides
//    what is computed (and clears stale databases); the other ranks of an MPI job follow it.
void machining_stages(const case_file::Case& c, const RunOptions& options, ClosedLoopInputs& in) {
  offline::SoloTeam solo;
  offline::JobTeam& team = options.team ? *options.team : solo;
  auto strip = [&](std::vector<std::string> tables) { return case_text_without(c.resolved_toml, tables, kPathKeys, c.origin); };
  std::vector<std::string> offline_tables = kLoopTables;
  offline_tables.push_back("truth");
  const std::string offline_text = strip(offline_tables), truth_text = strip(kLoopTables);
  std::optional<Stage> offline_stage, truth_stage;
  const std::string plan = offline::on_root_then_broadcast(team, [&] {
    // Before any long work, and before anything is removed: the folder takes files, the machine reads.
    if (!options.command.empty()) check_output_folder(options.out);
    check_sync_machine(c);
    if (!options.command.empty()) clear_earlier_run(options.out, options.command);
    offline_stage = stage_to_run(offline_text, options.out / "offline", options);
    truth_stage = stage_to_run(truth_text, options.out / "truth", options);
    return std::string{offline_stage ? '1' : '0', truth_stage ? '1' : '0'};
  });
  offline::on_every_rank(team, [&] {
    if (team.root()) return;
    if (plan[0] == '1') offline_stage = stage_in(offline_text, options.out / "offline", options);
    if (plan[1] == '1') truth_stage = stage_in(truth_text, options.out / "truth", options);
  });
  in.reused_offline = !offline_stage;
  in.reused_truth = !truth_stage;
  auto say = [&](const std::string& what) {
    if (!options.quiet && team.root()) std::cerr << "drom run: 1/2 " << what << "\n";
  };
  const auto stages_start = std::chrono::steady_clock::now();
  if (offline_stage && truth_stage) {
    say("offline snapshots and truth run, in one machining pass (" + offline_stage->options.out.string() + ", " + truth_stage->options.out.string() + ")");
    const auto [offline_result, truth_result] = offline::run_offline_and_truth(offline_stage->c, offline_stage->options, truth_stage->c, truth_stage->options);
    check_finished(offline_result, offline_stage->options.out, options.stop);
    check_finished(truth_result, truth_stage->options.out, options.stop);
    in.offline_seconds = seconds_since(stages_start);
    in.one_pass = true;
  } else {
    say("offline snapshots (" + (options.out / "offline").string() + (offline_stage ? ")" : ", reused)"));
    if (offline_stage) {
      check_finished(offline::run_job(offline_stage->c, offline::JobKind::Offline, offline_stage->options), offline_stage->options.out, options.stop);
      in.offline_seconds = seconds_since(stages_start);
    }
    say("truth run (" + (options.out / "truth").string() + (truth_stage ? ")" : ", reused)"));
    if (truth_stage) {
      const auto truth_start = std::chrono::steady_clock::now();
      check_finished(offline::run_job(truth_stage->c, offline::JobKind::Truth, truth_stage->options), truth_stage->options.out, options.stop);
      in.truth_seconds = seconds_since(truth_start);
    }
  }
}

}  // namespace

void help_prepare_closed_loop(const case_file::Case& c, const RunOptions& options) {
  ClosedLoopInputs ignored;
  machining_stages(c, options, ignored);
}

ClosedLoopInputs prepare_closed_loop(const case_file::Case& c, const RunOptions& options) {
  ClosedLoopInputs in;
  machining_stages(c, options, in);  // first: the other ranks of an MPI job wait for it
  in.shape = offline::build_part(c).shape;

  // 2. The light model, at the case's control.model_tolerance. Always reduced again (seconds): the
  //    model depends on the database and on how it is reduced.
  if (!options.quiet) std::cerr << "drom run: 2/2 light model (" << (options.out / "model").string() << ")\n";
  const auto model_file = options.out / "model" / "model.h5";
  {
    reduce::DatabaseReductionSettings settings;
    settings.tolerance = c.model_tolerance;
    // The stock's top as far as the laser reaches from the tool on the pocket's edge.
    if (c.use_stock_top) settings.top_margin = std::hypot(c.sensor_offset[0], c.sensor_offset[1]) + 0.5 * c.sensor_length;
    const auto start = std::chrono::steady_clock::now();
    const auto reduced = reduce::reduce_database(options.out / "offline" / "database.h5", settings);
    reduce::write_reduction(model_file, reduced, seconds_since(start));
    in.reduce_seconds = seconds_since(start);
  }
  in.model = reduce::LightModel::read(model_file);

  // The truth as the loop plays it.
  const auto truth_file = options.out / "truth" / "database.h5";
  const Hdf5Reader h5(truth_file);
  const Eigen::MatrixXd B1 = read_matrix(h5, "B1"), B2 = read_matrix(h5, "B2"), target_xyz = read_matrix(h5, "target_coordinates"),
                        nodes = read_matrix(h5, "node_coordinates");
  in.truth.station_times = read_matrix(h5, "station_time");
  const Eigen::Index nt = in.model.target.node_count(), ns = in.truth.station_times.size();
  if (target_xyz.rows() != nt || B1.rows() != nt * ns || B1.cols() != 1)
    throw InputError(truth_file.string() + ": its target surface does not match the model's (" + std::to_string(target_xyz.rows()) + " nodes against " +
                     std::to_string(nt) + ")");
  if ((target_xyz.transpose() - in.model.target.nodes()).cwiseAbs().maxCoeff() > 1e-6)
    throw InputError(truth_file.string() + ": its target nodes are not the model's (different mesh?)");
  in.truth.target_history = Eigen::Map<const Eigen::MatrixXd>(B1.data(), nt, ns);
  in.truth.amplitude = c.truth_amplitude;
  // The final shape at the model's surface nodes, matched by position.
  std::map<std::tuple<long long, long long, long long>, Eigen::Index> by_position;
  auto key = [](const Eigen::Vector3d& x) { return std::make_tuple(std::llround(x.x() * 1e5), std::llround(x.y() * 1e5), std::llround(x.z() * 1e5)); };
  for (Eigen::Index n = 0; n < nodes.rows(); ++n) by_position[key(nodes.row(n).transpose())] = n;
  in.truth.final_displacement.resize(3, in.model.shape_nodes.cols());
  for (Eigen::Index i = 0; i < in.model.shape_nodes.cols(); ++i) {
    const auto it = by_position.find(key(in.model.shape_nodes.col(i)));
    if (it == by_position.end()) throw InputError(truth_file.string() + ": a node of the model's final surface is not in the truth's mesh");
    in.truth.final_displacement.col(i) = B2.block(3 * it->second, 0, 3, 1);
  }
  // The stock's top at the model's top nodes, held after each node's cut as the model holds it (the
  // loop reads the top only where the tool has not been; near the cut's edge the held values are the
  // material's last before the cut, not removed material's).
  if (in.model.has_top()) {
    const Eigen::MatrixXd B1_top = read_matrix(h5, "B1_top"), top_ids = read_matrix(h5, "top_nodes");
    const Eigen::Index ntop = top_ids.rows(), nm = in.model.top.node_count();
    if (B1_top.rows() != ntop * ns || B1_top.cols() != 1) throw InputError(truth_file.string() + ": B1_top is not stations x top nodes");
    std::map<long long, Eigen::Index> row_of;  // truth mesh node -> its row among the truth's top nodes
    for (Eigen::Index i = 0; i < ntop; ++i) row_of[std::llround(top_ids(i, 0))] = i;
    in.truth.top_history.resize(nm, ns);
    for (Eigen::Index i = 0; i < nm; ++i) {
      const auto node = by_position.find(key(in.model.top.nodes().col(i)));
      const auto row = node == by_position.end() ? row_of.end() : row_of.find(node->second);
      if (row == row_of.end()) throw InputError(truth_file.string() + ": a node of the model's stock top is not on the truth's top");
      for (Eigen::Index s = 0; s < ns; ++s) in.truth.top_history(i, s) = B1_top(s * ntop + row->second, 0);
    }
    reduce::hold_after_cut(in.truth.top_history, in.truth.station_times, in.model.top_cut_time);
  }
  return in;
}

TruthPlay ClosedLoopInputs::play(double factor) const {
  TruthPlay p;
  p.history = std::make_unique<online::SurfaceHistory>(model.target, truth.target_history * factor, truth.station_times);
  p.part.target = p.history.get();
  if (truth.top_history.size() > 0) {
    p.top_history = std::make_unique<online::SurfaceHistory>(model.top, truth.top_history * factor, truth.station_times);
    p.part.top = p.top_history.get();
    p.part.top_cut_time = &model.top_cut_time;
  }
  p.part.final_displacement = truth.final_displacement * factor;
  // The stock's top straight above (x, y), found on the part's parametric outer surface.
  p.part.stock_top = [shape = shape](double x, double y) -> std::optional<double> {
    double u = x;
    for (int k = 0; k < 4; ++k) u += x - shape.from_parametric({u, y, shape.thickness()}).x();
    if (u < 0 || u > shape.length_u() || y < 0 || y > shape.length_v()) return std::nullopt;
    return shape.from_parametric({u, y, shape.thickness()}).z();
  };
  return p;
}

online::PredictorSettings predictor_settings(const case_file::Case& c, const reduce::LightModel& model) {
  online::PredictorSettings s;
  s.noise_sd = std::max(std::hypot(c.sensor_noise, model.error_bound()), 1e-6);
  s.use_stock_top = c.use_stock_top;
  s.top_noise_sd = std::max(std::hypot(c.sensor_noise, model.top_error_bound), 1e-6);
  s.prior_scale = c.prior_scale;
  s.reading_range = c.reading_range;
  s.learning_tolerance = c.learning_tolerance;
  s.learning_window = c.learning_window;
  s.max_offset_rate = c.max_offset_rate;
  s.max_offset = c.max_offset;
  return s;
}

void check_sync_machine(const case_file::Case& c) {
  if (!c.sync_machine.empty()) (void)machine::load_machine(c.sync_machine);
}

online::LoopSimulationSettings loop_settings(const case_file::Case& c, const reduce::LightModel& model) {
  online::LoopSimulationSettings s;
  if (!c.sync_machine.empty()) {
    const machine::Machine m = machine::load_machine(c.sync_machine);
    s.machine_motion = std::make_shared<const machine::ProgramClock>(model.path, m, c.feed_override);
    if (c.sync_reckoning == "machine")
      s.reckoning_motion = c.feed_override == 1 ? s.machine_motion : std::make_shared<const machine::ProgramClock>(model.path, m, 1.0);
  }
  s.sheet.offset = Eigen::Vector3d(c.sensor_offset[0], c.sensor_offset[1], c.sensor_offset[2]);
  s.sheet.angle_deg = c.sensor_angle;
  s.sheet.length = c.sensor_length;
  s.sheet.points = c.sensor_points;
  s.sheet.range = c.sensor_range;
  s.errors.offset_error = Eigen::Vector3d(c.sensor_offset_error[0], c.sensor_offset_error[1], c.sensor_offset_error[2]);
  s.errors.angle_error_deg = c.sensor_angle_error;
  s.errors.noise_sd = c.sensor_noise;
  s.period = c.sensor_period;
  s.refresh_rate = c.refresh_rate;
  s.desync = c.desync;
  s.feed_override = c.feed_override;
  s.correct = c.correct;
  s.seed = c.sensor_seed;
  return s;
}

LoopPair run_both_loops(const case_file::Case& c, const ClosedLoopInputs& in, double factor, const std::stop_token& stop,
                        const std::function<void(double)>& progress) {
  online::LoopSimulationSettings with = loop_settings(c, in.model), without = with;
  with.correct = true;
  without.correct = false;
  const online::LoopSimulation corrected_loop(in.model, predictor_settings(c, in.model), with), uncorrected_loop(in.model, predictor_settings(c, in.model), without);
  LoopPair pair;
  pair.corrected_settings = with;
  pair.corrected_truth = in.play(factor);
  const TruthPlay& a = pair.corrected_truth;
  const TruthPlay b = in.play(factor);
  // Either loop's failure stops the other too, as an outside stop stops both.
  std::stop_source both;
  const std::stop_callback forward(stop, [&] { both.request_stop(); });
  const std::stop_token token = both.get_token();
  std::exception_ptr side_failure;
  std::thread side([&] {
    try {
      pair.uncorrected = uncorrected_loop.run(b.part, [&](double) { throw_if_stop_requested(token); });
    } catch (...) {
      side_failure = std::current_exception();
      both.request_stop();
    }
  });
  try {
    pair.corrected = corrected_loop.run(a.part, [&](double f) {
      throw_if_stop_requested(token);
      if (progress) progress(f);
    });
  } catch (const StopRequested&) {
    side.join();
    // Stopped by the side's own failure, not from outside: that failure is the news.
    if (side_failure && !stop.stop_requested()) std::rethrow_exception(side_failure);
    throw;
  } catch (...) {
    both.request_stop();
    side.join();
    throw;
  }
  side.join();
  if (side_failure) std::rethrow_exception(side_failure);
  return pair;
}

}  // namespace drom::loop
