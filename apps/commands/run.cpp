// drom run and drom study: the closed loop on a case (loop/closed_loop_run.hpp, closed_loop_study.hpp).
#include "apps/commands.hpp"
#include "loop/closed_loop_run.hpp"
#include "loop/closed_loop_setup.hpp"
#include "loop/closed_loop_study.hpp"
#include "offline/process_team.hpp"

#include <cstdio>

namespace drom::app {

namespace {

loop::RunOptions run_options(const CommandOptions& options) {
  loop::RunOptions run;
  run.out = options.out, run.quiet = options.quiet, run.threads = options.threads, run.replan = options.replan;
  return run;
}

}  // namespace

int run_command(const CommandOptions& options) {
  // Under mpirun, every rank shares the offline-and-truth pass; rank 0 alone runs the rest.
  const auto team = offline::join_launched_team();
  case_file::Case c;
  offline::on_every_rank(*team, [&] { c = loop::load_run_case(options.case_path, options.overrides); });
  loop::RunOptions run = run_options(options);
  run.team = team.get();
  if (!team->root()) {
    loop::help_prepare_closed_loop(c, run);
    return 0;
  }
  const loop::RunResult r = loop::run_closed_loop(c, run);
  // A corrected program beyond a stroke is not written (exit 3, as drom finish, copy and orient).
  const int exit_code = r.program_verdict && !r.program_verdict->runnable() ? 3 : 0;
  if (exit_code != 0) std::fprintf(stderr, "drom run: corrected_program.nc on %s: %s\n", c.sync_machine.c_str(), r.program_verdict->summary_line().c_str());
  else if (r.program_verdict && r.program_verdict->slows_down())
    std::fprintf(stderr, "drom run: warning: corrected_program.nc asks %s for more than its limits at the programmed feed: %s\n", c.sync_machine.c_str(),
                 r.program_verdict->summary_line().c_str());
  if (options.quiet) return exit_code;
  const loop::Headline& h = r.headline;
  std::printf("drom run: %s (%s scale), model r = %d, %zu passes, sensor noise %.3g mm\n", c.name.c_str(), c.run_scale.c_str(), r.model_rank,
              r.corrected.passes.size(), c.sensor_noise);
  std::printf("  %-52s %s\n", "figure", "value");
  std::printf("  %-52s %.4f mm\n", "path error without correction, max", h.uncorrected_max);
  if (h.learned_at >= 0) std::printf("  %-52s %.1f s (pass %d)\n", "learned at program time", h.learned_at, h.learned_pass);
  else std::printf("  %-52s never\n", "learned at program time");
  std::printf("  %-52s %.2e mm (target %.0e)\n", "path error with correction, max from pass 3", h.corrected_max_from_3, c.path_tolerance);
  std::printf("  %-52s %.2e mm\n", "path error with correction, mean from pass 3", h.corrected_mean_from_3);
  const std::string shape_label = "final-shape max error, end of pass " + std::to_string(c.shape_pass);
  std::printf("  %-52s %.4f mm (target %.3g)\n", shape_label.c_str(), h.shape_error_at_pass, c.shape_tolerance);
  std::printf("  %-52s %.4f mm (95 %% band covers %.1f %%)\n", "final-shape max error, end", h.shape_error_end, 100 * h.band_coverage_end);
  if (r.corrected.calibration.points > 0)
    std::printf("  %-52s %.2e mm (slope x offset %.2e mm, ratio %.2f)\n", "calibration error's bias on the measured floor, RMS", r.corrected.calibration.rms_bias,
                r.corrected.calibration.rms_slope_times_offset, r.corrected.calibration.ratio);
  if (r.summary.contains("replanned_finish")) {
    const auto& q = r.summary["replanned_finish"];
    std::printf("  %-52s %.4f mm (the nominal path: %.4f mm)\n", "re-planned finish, max distance to the truth", q["max_distance_to_truth_mm"].get<double>(),
                q["nominal_max_distance_to_truth_mm"].get<double>());
    if (q.contains("laser_scan") && q["laser_scan"].contains("error")) {
      std::printf("  %-52s %s\n", "re-planned from the laser's scan", ("failed: " + q["laser_scan"]["error"].get<std::string>()).c_str());
    } else if (q.contains("laser_scan")) {
      const auto& l = q["laser_scan"];
      std::printf("  %-52s %.4f mm (%lld scan points, fit residual %.4f mm)\n", "re-planned from the laser's scan, max distance", l["max_distance_to_truth_mm"].get<double>(),
                  l["scan"]["points"].get<long long>(), l["fit"]["residual_rms_mm"].get<double>());
    }
  }
  if (r.program_verdict && r.program_verdict->runnable())
    std::printf("  %-52s %s\n", ("corrected program on " + c.sync_machine).c_str(), r.program_verdict->summary_line().c_str());
  std::printf("  outputs in %s: passes.csv/.png, final_shape_error.png, final_shape.pvd, offsets.csv, %ssummary.json (%.0f s)\n",
              options.out.string().c_str(), exit_code == 0 ? "corrected_program.nc, " : "", r.summary["timing_s"]["total"].get<double>());
  return exit_code;
}

int study_command(const CommandOptions& options) {
  const case_file::Case base = loop::load_run_case(options.case_path, options.overrides);
  const auto summary = loop::run_study(base, options.study_parameter, options.study_values, run_options(options));
  if (options.quiet) return 0;
  std::printf("drom study: %s, %s\n", base.name.c_str(), summary["parameter_label"].get<std::string>().c_str());
  std::printf("  %12s  %14s  %14s  %14s  %14s\n", options.study_parameter.c_str(), "uncorr. max", "corr. max p3+", ("shape p" + std::to_string(base.shape_pass)).c_str(),
              "shape end");
  for (const auto& r : summary["rows"])
    std::printf("  %12.6g  %14.3e  %14.3e  %14.4f  %14.4f\n", r["value"].get<double>(), r["path_error_uncorrected_max_mm"].get<double>(),
                r["path_error_corrected_max_from_pass3_mm"].get<double>(), r["final_shape_max_error_end_of_target_pass_mm"].get<double>(),
                r["final_shape_max_error_end_mm"].get<double>());
  std::printf("  outputs in %s: study.csv, study.png, summary.json\n", options.out.string().c_str());
  return 0;
}

}  // namespace drom::app
