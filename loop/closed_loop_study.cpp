// drom study (loop/closed_loop_study.hpp): one closed-loop parameter swept, everything else as the case says (docs/design.md §6-§7).
//   1. the case at the run's scale, its offline database, model and truth (shared with drom run:
//      the same --out reuses them, since none of the swept parameters changes them);
//   2. per value, the loop with and without correction;
//   3. study.csv and study.png (the headline errors against the parameter), summary.json.
// The stress amplitude scales the truth's displacements (they are linear in the stresses), so it
// does not rerun the truth either.
#include "loop/closed_loop_study.hpp"

#include "loop/closed_loop_report.hpp"
#include "support/summary.hpp"
#include "support/atomic_file.hpp"
#include "support/input_error.hpp"
#include "support/png_plot.hpp"
#include "support/resources.hpp"

#include <chrono>
#include <cstdio>
#include <iostream>
#include <map>

namespace drom::loop {

namespace {

struct Parameter {
  const char* label;
  void (*apply)(case_file::Case&, double);
};

const std::map<std::string, Parameter>& parameters() {
  static const std::map<std::string, Parameter> p = {
      {"noise", {"sensor noise sigma (mm)", [](case_file::Case& c, double v) { c.sensor_noise = v; }}},
      {"angle", {"sheet angle to the feed (deg)", [](case_file::Case& c, double v) { c.sensor_angle = v; }}},
      {"refresh", {"offset refresh rate (Hz)", [](case_file::Case& c, double v) { c.refresh_rate = v; }}},
      {"calibration", {"sensor offset error along the feed (mm)", [](case_file::Case& c, double v) { c.sensor_offset_error[0] = v; }}},
      {"desync", {"synchronization delay (s)", [](case_file::Case& c, double v) { c.desync = v; }}},
      {"amplitude", {"stress amplitude (x the truth's)", [](case_file::Case&, double) {}}},
      {"seed", {"sensor noise draw (seed)", [](case_file::Case& c, double v) { c.sensor_seed = static_cast<std::uint32_t>(v); }}},
  };
  return p;
}

}  // namespace

std::vector<std::string> study_parameters() {
  std::vector<std::string> names;
  for (const auto& [name, p] : parameters()) names.push_back(name);
  return names;
}

nlohmann::json run_study(const case_file::Case& base, const std::string& parameter_name, const std::vector<double>& values, const RunOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  const auto it = parameters().find(parameter_name);
  if (it == parameters().end()) {
    std::string names;
    for (const auto& [name, p] : parameters()) names += (names.empty() ? "" : ", ") + name;
    throw InputError("--param: expected one of " + names + ", got '" + parameter_name + "'");
  }
  if (values.empty()) throw InputError("--values: expected at least one value, e.g. --values 0,0.02,0.05");
  const Parameter& parameter = it->second;
  RunOptions as_study = options;
  as_study.command = "study";  // the folder checked and the earlier study's outputs cleared, before the stages
  const ClosedLoopInputs in = prepare_closed_loop(base, as_study);

  std::string csv = parameter_name +
                    ",learned_at_s,learned_pass,uncorrected_max_mm,corrected_max_from_pass3_mm,corrected_mean_from_pass3_mm,final_shape_error_target_pass_mm,"
                    "final_shape_error_end_mm,band95_coverage_end,calibration_rms_bias_mm,calibration_rms_slope_times_offset_mm\n";
  PlotSeries path{"path error with correction, max from pass 3", {}, {}, "o-"}, shape3{"final-shape error, end of pass " + std::to_string(base.shape_pass), {}, {}, "s-"},
      shape_end{"final-shape error, end", {}, {}, "^-"}, open_loop{"path error without correction, max", {}, {}, "x--"};
  nlohmann::json rows = nlohmann::json::array();
  for (const double value : values) {
    case_file::Case c = base;
    parameter.apply(c, value);
    const double factor = parameter_name == "amplitude" ? value : 1.0;
    const LoopPair loops = run_both_loops(c, in, factor, options.stop);
    const online::LoopSimulationResult &corrected = loops.corrected, &uncorrected = loops.uncorrected;
    const Headline h = headline(corrected, uncorrected, c.shape_pass);
    char line[512];
    std::snprintf(line, sizeof line, "%.6g,%.3f,%d,%.6e,%.6e,%.6e,%.6e,%.6e,%.4f,%.6e,%.6e\n", value, h.learned_at, h.learned_pass, h.uncorrected_max,
                  h.corrected_max_from_3, h.corrected_mean_from_3, h.shape_error_at_pass, h.shape_error_end, h.band_coverage_end, corrected.calibration.rms_bias,
                  corrected.calibration.rms_slope_times_offset);
    csv += line;
    path.x.push_back(value), path.y.push_back(std::max(h.corrected_max_from_3, 1e-7));
    shape3.x.push_back(value), shape3.y.push_back(std::max(h.shape_error_at_pass, 1e-7));
    shape_end.x.push_back(value), shape_end.y.push_back(std::max(h.shape_error_end, 1e-7));
    open_loop.x.push_back(value), open_loop.y.push_back(h.uncorrected_max);
    nlohmann::json row = h.to_json();
    row["value"] = value;
    row["calibration"] = {{"rms_bias_mm", corrected.calibration.rms_bias}, {"rms_slope_times_offset_mm", corrected.calibration.rms_slope_times_offset},
                          {"ratio", corrected.calibration.ratio}};
    rows.push_back(row);
    if (!options.quiet)
      std::fprintf(stderr, "drom study: %s = %g: path error from pass 3 %.2e mm, final shape at pass 3 %.4f mm, at the end %.4f mm\n", parameter_name.c_str(),
                   value, h.corrected_max_from_3, h.shape_error_at_pass, h.shape_error_end);
  }
  write_file_atomically(options.out / "study.csv", csv);
  std::vector<std::string> files = {"study.csv"};
  PlotSpec plot;
  plot.title = base.name + ": headline errors against the " + parameter.label;
  plot.x_label = parameter.label;
  plot.y_label = "mm";
  plot.series = {path, shape3, shape_end, open_loop};
  plot.hlines = {{"path tolerance", base.path_tolerance}, {"shape tolerance", base.shape_tolerance}};
  plot.log_y = true;
  if (write_png_plot(options.out / "study.png", plot)) files.push_back("study.png");
  files.push_back("summary.json");
  const nlohmann::json summary{{"command", "study"},
                              {"case", base.name},
                              {"scale", base.run_scale},
                              {"parameter", parameter_name},
                              {"rows", rows},
                              {"model_rank", in.model.rank()},
                              {"time_s", seconds_since(start)},
                              {"machine", machine_info()},
                              {"files", files},
                               {"parameter_label", parameter.label}};
  write_summary(options.out, summary);
  return summary;
}

}  // namespace drom::loop
