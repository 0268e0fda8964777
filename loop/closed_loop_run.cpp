// drom run (loop/closed_loop_run.hpp): the main job, the seed's §3.5 experiment (docs/design.md §6-§7).
//   1. the case at the run's scale ([run] scale = "quick": a few minutes on two cores; "seed": as written);
//   2. offline snapshots of the basis's unit profiles, and the light model (drom offline, drom reduce);
//   3. the truth: the same machining with the [truth] profile, a profile outside the basis;
//   4. the closed loop twice, on the same sensor noise: offsets commanded (with correction) and held
//      at 0 (without), the predictor learning in both;
//   5. outputs: per-pass errors, final-shape predictions against the truth, offsets, the corrected
//      program, summary.json, and a short table on stdout.
// Stages 2-3 are kept under --out and reused while the case that made them is unchanged, so a rerun
// with other sensor or control settings costs only the loop.
#include "loop/closed_loop_run.hpp"
#include "loop/final_scan.hpp"
#include "loop/replanned_finish.hpp"
#include "machine/cl_data.hpp"
#include "paths/copy/cloud_path.hpp"
#include "support/atomic_file.hpp"

#include "support/summary.hpp"
#include "support/resources.hpp"
#include "support/stop_request.hpp"

#include <chrono>
#include <cstdio>
#include <iostream>
#include <exception>
#include <thread>

namespace drom::loop {

namespace {

nlohmann::json replanned_json(const ReplannedFinish& r, double tool_diameter) {
  return {{"cloud_points", r.cloud_points},
          {"upward_faces", r.faces},
          {"tool", "ball"},
          {"tool_diameter_mm", tool_diameter},
          {"passes", r.replanned.passes},
          {"path_points", r.replanned.path.size()},
          {"gaps", r.replanned.gaps},
          {"cut_nodes_judged", r.judged},
          {"max_distance_to_truth_mm", r.max_error},
          {"rms_distance_to_truth_mm", r.rms_error},
          {"nominal_max_distance_to_truth_mm", r.nominal_max_error},
          {"nominal_rms_distance_to_truth_mm", r.nominal_rms_error}};
}

}  // namespace

namespace {

nlohmann::json loop_json(const online::LoopSimulationResult& r) {
  nlohmann::json passes = nlohmann::json::array();
  for (const auto& p : r.passes)
    passes.push_back({{"pass", p.pass},
                      {"mean_abs_error_mm", p.mean_abs_error},
                      {"max_abs_error_mm", p.max_abs_error},
                      {"max_abs_distortion_mm", p.max_abs_distortion},
                      {"final_shape_max_error_mm", p.shape_max_error},
                      {"final_shape_rms_error_mm", p.shape_rms_error},
                      {"band95_coverage", p.shape_band_coverage},
                      {"learned", p.learned},
                      {"profiles", p.profiles},
                      {"points_used", p.points_used}});
  return {{"passes", passes},
          {"profiles", r.profiles},
          {"points", {{"used", r.points.used}, {"used_on_stock_top", r.points.used_top}, {"outside_target", r.points.outside}, {"not_yet_cut", r.points.not_yet_cut}, {"invalid", r.points.invalid},
                      {"out_of_range", r.points.out_of_range}}},
          {"learned_at_program_time_s", r.learned_at},
          {"rejected", {{"profiles_glitch", r.rejections.glitch}, {"profiles_stuck", r.rejections.stuck}, {"profiles_empty", r.rejections.empty},
                        {"profiles_out_of_order", r.rejections.out_of_order}, {"profiles_repeated", r.rejections.repeated},
                        {"profiles_non_finite", r.rejections.non_finite}, {"fit_in_doubt", r.rejections.unlearned},
                        {"doubts_resolved", r.rejections.doubts_resolved},
                        {"offsets_clamped", r.rejections.offsets_clamped}, {"offsets_late", r.rejections.offsets_late}}},
          {"offset_bound_mm", r.offset_bound},
          {"calibration_bias", {{"sampled_points", r.calibration.points}, {"rms_bias_mm", r.calibration.rms_bias},
                                {"rms_slope_times_offset_mm", r.calibration.rms_slope_times_offset}, {"ratio_bias_to_slope_times_offset", r.calibration.ratio}}},
          {"alpha", std::vector<double>(r.estimate.alpha.data(), r.estimate.alpha.data() + r.estimate.alpha.size())},
          {"seconds", r.seconds}};
}

// How the machine moved and how well the synchronizer followed it: the real against the programmed
// time, and the believed position's error as run and as a programmed-feed reckoning would have had it.
nlohmann::json sync_json(const case_file::Case& c, const online::LoopSimulationSettings& s, const online::LoopSimulationResult& r) {
  auto errors = [](const online::SyncError& e) {
    return nlohmann::json{{"max_program_time_error_s", e.max_time}, {"max_shift_mm", e.max_shift}, {"rms_shift_mm", e.rms_shift}, {"steps_on_floor", e.samples}};
  };
  nlohmann::json j{{"desync_s", c.desync}, {"feed_override", c.feed_override}, {"machine", c.sync_machine.empty() ? "none: the programmed feed" : c.sync_machine},
                   {"reckoning", c.sync_machine.empty() ? "programmed" : c.sync_reckoning}, {"believed_position", errors(r.sync)},
                   {"believed_position_if_reckoning_at_the_programmed_feed", errors(r.sync_programmed_feed)}};
  if (s.machine_motion) {
    j["program_time_s"] = s.machine_motion->program_duration();
    j["real_time_s"] = s.machine_motion->real_duration();
  }
  return j;
}

}  // namespace

// The finishing pass re-planned on the predicted final shape, and on the unclamped part as the loop's
// laser scans it (the final-shape basis fitted to the scan), each judged against the truth's; their
// CL files are added to `files`.
nlohmann::json replan_finishes(const case_file::Case& c, const ClosedLoopInputs& in, const LoopPair& loops, const RunOptions& options,
                               std::vector<std::string>& files) {
  const online::LoopSimulationResult& corrected = loops.corrected;
  nlohmann::json replan;
  if (!options.quiet) std::cerr << "drom run: the finishing pass re-planned on the predicted final shape\n";
  const online::FinalShape& predicted = corrected.shapes.back();
  const Eigen::Matrix3Xd& truth = in.truth.final_displacement;
  ReplanSettings replan_settings;
  replan_settings.finishing.tool.cutter = {paths::ToolKind::ball, c.replan_tool_diameter / 2, c.replan_tool_diameter / 2};
  replan_settings.finishing.scallop = c.replan_scallop;
  replan_settings.finishing.chord_tolerance = c.replan_tolerance;
  replan_settings.finishing.longitudinal_step = c.replan_step;
  replan_settings.sample_spacing = c.replan_sample_spacing;
  ReplannedFinish r = replan_finish(predicted, truth, replan_settings);
  write_file_atomically(options.out / "replanned_finish_cl.csv",
                        machine::cl_csv(paths::to_cl_program(r.replanned.path, Eigen::Matrix3d::Identity(), 1000, "drom run --replan (predicted shape)")));
  files.push_back("replanned_finish_cl.csv");
  replan = replanned_json(r, c.replan_tool_diameter);
  replan["sample_spacing_mm"] = sample_spacing(replan_settings);
  const double model_based = r.max_error;
  r.replanned = {};  // the path is written: its memory goes before the laser's finish takes as much
  replan["max_upward_error_mm"] = max_upward_difference(predicted, predicted.displacement, truth);

  try {
    if (!options.quiet) std::cerr << "drom run: the unclamped part scanned by the laser, the final-shape basis fitted, the finish re-planned on it\n";
    const auto scan_start = std::chrono::steady_clock::now();
    FinalScanSettings scan_settings;
    scan_settings.seed = c.sensor_seed + 1;  // a draw of its own, after the loop's
    scan_settings.step = c.replan_scan_step;
    const Eigen::Matrix3Xd on_part = predicted.nodes + truth;
    const double margin = 5;
    FinalScan scan = scan_final_part(upward_height_field(predicted, truth, scan_settings.min_up), on_part.topRows<2>().rowwise().minCoeff().array() - margin,
                                           on_part.topRows<2>().rowwise().maxCoeff().array() + margin, on_part.row(2).maxCoeff(), loops.corrected_settings.sheet,
                                           loops.corrected_settings.errors, scan_settings);
    // The scan alone, and the scan updating the loop's own estimate (the points the laser read while
    // the part was clamped): the finish is re-planned on the latter, every laser point weighing in.
    const ScanFit alone = fit_final_shape(predicted, in.model.final_basis, scan.points, scan_settings);
    const ScanPrior loop_estimate{corrected.estimate.alpha, corrected.estimate.covariance, std::max(loops.corrected_settings.errors.noise_sd, 1e-6)};
    const ScanFit fit = fit_final_shape(predicted, in.model.final_basis, scan.points, scan_settings, &loop_estimate);
    const double fit_seconds = seconds_since(scan_start);
    const long long scan_points = static_cast<long long>(scan.points.size());
    std::vector<online::MeasuredPoint>().swap(scan.points);
    const ReplannedFinish laser = replan_finish(fit.shape, truth, replan_settings);
    write_file_atomically(options.out / "replanned_finish_laser_cl.csv",
                          machine::cl_csv(paths::to_cl_program(laser.replanned.path, Eigen::Matrix3d::Identity(), 1000, "drom run --replan (laser scan)")));
    files.push_back("replanned_finish_laser_cl.csv");
    const auto fit_json = [&](const ScanFit& f) {
      return nlohmann::json{{"points_used", f.used}, {"off_part", f.off_part}, {"outliers", f.outliers}, {"residual_rms_mm", f.residual_rms},
                            {"iterations", f.iterations}, {"unobserved_directions", f.unobserved}, {"max_sd_mm", f.shape.sd.cwiseAbs().maxCoeff()},
                            {"max_upward_error_mm", max_upward_difference(predicted, f.shape.displacement, truth)}};
    };
    replan["laser_scan"] = replanned_json(laser, c.replan_tool_diameter);
    replan["laser_scan"]["scan"] = {{"profiles", scan.profiles}, {"points", scan_points}, {"no_reading", scan.no_reading},
                                    {"step_mm", scan_settings.step}, {"noise_mm", loops.corrected_settings.errors.noise_sd}};
    replan["laser_scan"]["fit"] = fit_json(fit);
    replan["laser_scan"]["fit"]["basis_columns"] = fit.alpha.size();
    replan["laser_scan"]["fit"]["scan_and_fits_seconds"] = fit_seconds;
    replan["laser_scan"]["fit_scan_alone"] = fit_json(alone);
    replan["laser_scan"]["within_twice_model_based"] = laser.max_error <= 2 * model_based;
  } catch (const std::invalid_argument& e) {
    // The model-based finish and the loop's outputs stand; the scan's failure is reported beside them.
    replan["laser_scan"] = {{"error", e.what()}};
    if (!options.quiet) std::cerr << "drom run: the re-plan from the laser's scan failed: " << e.what() << "\n";
  }
  return replan;
}

RunResult run_closed_loop(const case_file::Case& c, const RunOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  RunOptions as_run = options;
  as_run.command = "run";  // the folder checked and the earlier run's outputs cleared, before the stages
  const ClosedLoopInputs in = prepare_closed_loop(c, as_run);

  // The two loops share everything but the correction; each has its own copy of the truth.
  if (!options.quiet) std::cerr << "drom run: the closed loop, with and without correction (" << online::floor_passes(in.model).size() << " passes)\n";
  LoopPair loops = run_both_loops(c, in, 1.0, options.stop, [&](double f) {
    if (!options.quiet) std::fprintf(stderr, "\r  %3.0f %%", 100 * f);
  });
  online::LoopSimulationResult& corrected = loops.corrected;
  online::LoopSimulationResult& uncorrected = loops.uncorrected;
  if (!options.quiet) std::fprintf(stderr, "\r  100 %%\n");

  LoopOutputs outputs = write_loop_outputs(options.out, c, in.model, loops.corrected_truth.part, corrected, uncorrected);
  std::vector<std::string>& files = outputs.files;
  nlohmann::json replan;
  if (options.replan && !loops.corrected.shapes.empty()) replan = replan_finishes(c, in, loops, options, files);
  files.push_back("summary.json");
  const Headline h = headline(corrected, uncorrected, c.shape_pass);
  nlohmann::json summary = {
      {"command", "run"},
      {"case", c.name},
      {"case_origin", c.origin},
      {"scale", c.run_scale},
      {"headline", h.to_json()},
      {"targets", {{"path_tolerance_mm", c.path_tolerance}, {"shape_tolerance_mm", c.shape_tolerance},
                   {"path_error_from_pass3_met", h.corrected_max_from_3 <= c.path_tolerance},
                   {"shape_pass", c.shape_pass},
                   {"final_shape_by_target_pass_met", h.shape_error_at_pass <= c.shape_tolerance}}},
      {"model", {{"rank", in.model.rank()}, {"error_bound_mm", in.model.error_bound()}, {"tolerance_mm", in.model.tolerance}}},
      {"truth", {{"amplitude", c.truth_amplitude}, {"max_abs_final_vertical_mm", in.truth.final_displacement.row(2).cwiseAbs().maxCoeff()},
                 {"max_abs_target_w_mm", in.truth.target_history.cwiseAbs().maxCoeff()}}},
      {"sensor", {{"noise_mm", c.sensor_noise}, {"period_s", c.sensor_period}, {"angle_deg", c.sensor_angle}, {"offset_mm", c.sensor_offset},
                  {"offset_error_mm", c.sensor_offset_error}, {"angle_error_deg", c.sensor_angle_error}}},
      {"sync", sync_json(c, loops.corrected_settings, corrected)},
      {"control", {{"refresh_rate_hz", c.refresh_rate}, {"max_offset_rate_mm_s", c.max_offset_rate}, {"learning_tolerance_mm", c.learning_tolerance}}},
      {"corrected", loop_json(corrected)},
      {"uncorrected", loop_json(uncorrected)},
      {"timing_s", {{"offline", in.offline_seconds}, {"truth", in.truth_seconds}, {"reduce", in.reduce_seconds}, {"loop_corrected", corrected.seconds},
                    {"loop_uncorrected", uncorrected.seconds}, {"total", seconds_since(start)},
                    {"offline_and_truth_in_one_pass", in.one_pass}}},
      {"reused", {{"offline", in.reused_offline}, {"truth", in.reused_truth}}},
      {"peak_memory_mb", static_cast<double>(peak_memory_bytes()) / 1048576.0},
      {"machine", machine_info()},
      {"files", files}};
  if (!replan.is_null()) summary["replanned_finish"] = replan;
  if (outputs.program_verdict) summary["program_verdict"] = outputs.program_verdict->to_json();
  write_summary(options.out, summary);
  RunResult result;
  result.headline = h;
  result.summary = std::move(summary);
  result.corrected = std::move(corrected);
  result.uncorrected = std::move(uncorrected);
  result.model_rank = in.model.rank();
  result.program_verdict = outputs.program_verdict;
  return result;
}

}  // namespace drom::loop
