#include "loop/closed_loop_report.hpp"

#include "fem/vtk_output.hpp"
#include "support/atomic_file.hpp"
#include "support/png_plot.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace drom::loop {

nlohmann::json Headline::to_json() const {
  return {{"learned_at_program_time_s", learned_at},
          {"learned_during_pass", learned_pass},
          {"path_error_uncorrected_max_mm", uncorrected_max},
          {"path_error_corrected_max_from_pass3_mm", corrected_max_from_3},
          {"path_error_corrected_mean_from_pass3_mm", corrected_mean_from_3},
          {"final_shape_target_pass", shape_pass},
          {"final_shape_max_error_end_of_target_pass_mm", shape_error_at_pass},
          {"final_shape_max_error_end_mm", shape_error_end},
          {"final_shape_rms_error_end_mm", shape_rms_end},
          {"final_shape_band95_coverage_end", band_coverage_end}};
}

Headline headline(const online::LoopSimulationResult& corrected, const online::LoopSimulationResult& uncorrected, int shape_pass) {
  Headline h;
  h.shape_pass = shape_pass;
  h.learned_at = corrected.learned_at;
  for (const auto& p : corrected.passes)
    if (h.learned_at >= 0 && h.learned_at <= p.end) {
      h.learned_pass = p.pass;
      break;
    }
  for (const auto& p : uncorrected.passes) h.uncorrected_max = std::max(h.uncorrected_max, p.max_abs_error);
  double sum = 0;
  long long n = 0;
  for (const auto& p : corrected.passes)
    if (p.pass >= 3) {
      h.corrected_max_from_3 = std::max(h.corrected_max_from_3, p.max_abs_error);
      sum += p.mean_abs_error * p.samples, n += p.samples;
    }
  h.corrected_mean_from_3 = n > 0 ? sum / static_cast<double>(n) : 0;
  if (shape_pass >= 1 && corrected.passes.size() >= static_cast<std::size_t>(shape_pass))
    h.shape_error_at_pass = corrected.passes[static_cast<std::size_t>(shape_pass - 1)].shape_max_error;
  if (!corrected.passes.empty()) {
    h.shape_error_end = corrected.passes.back().shape_max_error;
    h.shape_rms_end = corrected.passes.back().shape_rms_error;
    h.band_coverage_end = corrected.passes.back().shape_band_coverage;
  }
  return h;
}

std::string corrected_gcode(const reduce::LightModel& model, const std::vector<online::Pass>& passes, const std::vector<online::OffsetCommand>& offsets,
                            const machine::PostOptions& post) {
  // The offset in force at program time t: each command's step taken in a ramp of kRamp (or up to
  // the next command, if sooner) rather than at once. A step written as it comes would fall into
  // whatever piece follows it, and a command just before a waypoint makes that piece a Z jump
  // (measured on the flat plate: 7 400 mm/s asked of a 500 mm/s Z). The ramp keeps the Z speed the
  // offsets add under a step / kRamp: the predictor's rate limit over a refresh period (0.1 mm at
  // 1 mm/s and 10 Hz) gives 5 mm/s; it departs from the commanded steps only for kRamp after each.
  constexpr double kRamp = 0.02;  // s
  auto command_before = [&](double t) {  // the last command at or before t: offsets.end() for none
    const auto it = std::upper_bound(offsets.begin(), offsets.end(), t, [](double v, const online::OffsetCommand& o) { return v < o.believed_time; });
    return it == offsets.begin() ? offsets.end() : std::prev(it);
  };
  auto ramp_of = [&](std::vector<online::OffsetCommand>::const_iterator k) {
    const auto next = std::next(k);
    return next == offsets.end() ? kRamp : std::min(kRamp, next->believed_time - k->believed_time);
  };
  auto offset_at = [&](double t) {
    const auto k = command_before(t);
    if (k == offsets.end()) return 0.0;
    // Several commands can share a believed time (the reckoning holds it at a waypoint until the
    // next edge): the step is from the last one before that time to the last one at it.
    auto earlier = k;
    while (earlier != offsets.begin() && std::prev(earlier)->believed_time == k->believed_time) --earlier;
    const double before = earlier == offsets.begin() ? 0.0 : std::prev(earlier)->offset, ramp = ramp_of(k);
    const double f = ramp > 0 ? std::clamp((t - k->believed_time) / ramp, 0.0, 1.0) : 1.0;
    return before + f * (k->offset - before);
  };
  auto on_floor = [&](double t) {
    return std::any_of(passes.begin(), passes.end(), [&](const online::Pass& p) { return t >= p.start && t <= p.end; });
  };
  std::string g = machine::program_header(post, "", "G43 H" + std::to_string(post.tool),
                                         "(drom corrected program: the tool-length compensation the predictor commanded, written into Z)\n"
                                         "(cutting feeds reproduce the programmed timing, retracts and moves across are rapids; units mm, absolute)\n");
  char line[160];
  const Eigen::MatrixXd& path = model.path;
  const double top = path.col(2).maxCoeff(), plane = top + post.clearance;
  double entry_feed = 0;  // the path's first feed, for the plunge to its start
  for (Eigen::Index i = 0; i + 1 < path.rows() && !(entry_feed > 0); ++i)
    if (path(i + 1, 3) > path(i, 3)) entry_feed = 60 * (path.row(i + 1).head<3>() - path.row(i).head<3>()).norm() / (path(i + 1, 3) - path(i, 3));
  std::snprintf(line, sizeof line, "G0 Z%.4f\nG0 X%.4f Y%.4f\nG1 Z%.4f F%.1f\n", plane, path(0, 0), path(0, 1), path(0, 2), entry_feed > 0 ? entry_feed : 500.0);
  g += line;
  double last_z = path(0, 2);
  double tool_z = last_z;  // where the program has the tool: the path's z, or the clearance plane after a rapid
  for (Eigen::Index i = 0; i + 1 < path.rows(); ++i) {
    const double t0 = path(i, 3), t1 = path(i + 1, 3);
    const Eigen::Vector3d a = path.row(i).head<3>().transpose(), b = path.row(i + 1).head<3>().transpose();
    if (t1 <= t0) continue;
    // Split the segment where a ramp starts or ends along it.
    std::vector<double> cuts;
    if (on_floor(0.5 * (t0 + t1)))
      for (auto it = std::upper_bound(offsets.begin(), offsets.end(), t0 - kRamp, [](double v, const online::OffsetCommand& o) { return v < o.believed_time; });
           it != offsets.end() && it->believed_time < t1; ++it)
        for (const double t : {it->believed_time, it->believed_time + ramp_of(it)})
          if (t > t0 && t < t1 && (cuts.empty() || t > cuts.back())) cuts.push_back(t);
    cuts.push_back(t1);
    double from = t0;
    Eigen::Vector3d prev = a;
    for (double t : cuts) {
      const double f = (t - t0) / (t1 - t0);
      const Eigen::Vector3d p = a + f * (b - a);
      // On the floor, and at the end of the plunge onto it: the plunge goes down to the corrected
      // depth at its own feed, not to the nominal one with the correction as a jump after it.
      const bool floor_piece = on_floor(0.5 * (from + t)) || on_floor(t);
      const double z = p.z() + (floor_piece ? offset_at(t) : 0.0);
      const double length = std::hypot((p - prev).head<2>().norm(), z - last_z);
      if (length > 1e-6 || std::abs(z - last_z) > 1e-6) {  // else its time goes to the segment's next piece
        // Off the floor, a straight retract and a move across at the path's top are rapids, as a
        // shop writes them (and as its controller times them): up to the clearance plane, across
        // there, and down to the path's top again before the plunge, which keeps its feed.
        const bool retract = (p - prev).head<2>().norm() < 1e-9 && z > last_z;
        const bool across = z >= top - 1e-9 && last_z >= top - 1e-9;
        if (!floor_piece && (retract || across)) {
          if (tool_z < plane) std::snprintf(line, sizeof line, "G0 Z%.4f\n", plane), g += line, tool_z = plane;
          if ((p - prev).head<2>().norm() >= 1e-9) std::snprintf(line, sizeof line, "G0 X%.4f Y%.4f\n", p.x(), p.y()), g += line;
        } else {
          if (tool_z != last_z) std::snprintf(line, sizeof line, "G0 Z%.5f\n", last_z), g += line;
          std::snprintf(line, sizeof line, "G1 X%.4f Y%.4f Z%.5f F%.1f\n", p.x(), p.y(), z, 60 * length / std::max(1e-9, t - from));
          g += line;
          tool_z = z;
        }
        last_z = z, prev = p, from = t;
      }
    }
  }
  if (tool_z < plane) std::snprintf(line, sizeof line, "G0 Z%.4f\n", plane), g += line;
  g += machine::program_end(post);
  return g;
}

namespace {

// Per pass: path error with and without correction, and the final-shape prediction at its end.
void write_pass_table(const std::filesystem::path& out, const case_file::Case& c, const online::LoopSimulationResult& corrected,
                      const online::LoopSimulationResult& uncorrected, std::vector<std::string>& files) {
  char line[512];
  std::string csv =
      "pass,start_s,end_s,uncorrected_mean_mm,uncorrected_max_mm,corrected_mean_mm,corrected_max_mm,learned_by_end,"
      "final_shape_max_error_mm,final_shape_rms_error_mm,band95_coverage,uncorrected_final_shape_max_error_mm\n";
  PlotSeries um{"without correction, max", {}, {}, "o-"}, cm{"with correction, max", {}, {}, "s-"}, cmean{"with correction, mean", {}, {}, "s--"};
  for (std::size_t p = 0; p < corrected.passes.size(); ++p) {
    const auto &a = corrected.passes[p], &b = uncorrected.passes[p];
    std::snprintf(line, sizeof line, "%d,%.3f,%.3f,%.6e,%.6e,%.6e,%.6e,%d,%.6e,%.6e,%.4f,%.6e\n", a.pass, a.start, a.end, b.mean_abs_error, b.max_abs_error,
                  a.mean_abs_error, a.max_abs_error, a.learned ? 1 : 0, a.shape_max_error, a.shape_rms_error, a.shape_band_coverage, b.shape_max_error);
    csv += line;
    if (b.samples > 0) um.x.push_back(a.pass), um.y.push_back(b.max_abs_error);
    if (a.samples > 0) cm.x.push_back(a.pass), cm.y.push_back(std::max(a.max_abs_error, 1e-7)), cmean.x.push_back(a.pass), cmean.y.push_back(std::max(a.mean_abs_error, 1e-7));
  }
  write_file_atomically(out / "passes.csv", csv);
  files.push_back("passes.csv");
  PlotSpec plot;
  plot.title = c.name + ": altitude error of the tool-workpiece contact point per pass (noise " + std::to_string(c.sensor_noise).substr(0, 5) + " mm)";
  plot.x_label = "pass";
  plot.y_label = "|error| (mm)";
  plot.series = {um, cm, cmean};
  plot.hlines = {{"path tolerance", c.path_tolerance}};
  plot.log_y = true;
  if (write_png_plot(out / "passes.png", plot)) files.push_back("passes.png");
}

void write_shape_error_plot(const std::filesystem::path& out, const case_file::Case& c, const online::LoopSimulationResult& corrected,
                            std::vector<std::string>& files) {
  PlotSeries se{"final-shape max error (with correction)", {}, {}, "o-"}, sr{"RMS error", {}, {}, "s--"};
  for (const auto& a : corrected.passes) se.x.push_back(a.pass), se.y.push_back(std::max(a.shape_max_error, 1e-7)), sr.x.push_back(a.pass), sr.y.push_back(std::max(a.shape_rms_error, 1e-7));
  PlotSpec shape;
  shape.title = c.name + ": predicted final shape against the truth's, at the end of each pass";
  shape.x_label = "pass";
  shape.y_label = "vertical displacement error (mm)";
  shape.series = {se, sr};
  shape.hlines = {{"shape tolerance", c.shape_tolerance}};
  shape.log_y = true;
  if (write_png_plot(out / "final_shape_error.png", shape)) files.push_back("final_shape_error.png");
}

// Every step on the floor, both runs (the seed's figs. 3.44 and 3.61 plot this along the path).
void write_path_samples(const std::filesystem::path& out, const online::LoopSimulationResult& corrected, const online::LoopSimulationResult& uncorrected,
                        std::vector<std::string>& files) {
  char line[512];
  std::string csv = "run,clock_s,program_time_s,pass,x_mm,y_mm,offset_mm,offset_sd_mm,distortion_mm,error_mm,learned\n";
  for (const auto* r : {&uncorrected, &corrected})
    for (const auto& s : r->samples) {
      std::snprintf(line, sizeof line, "%s,%.3f,%.3f,%d,%.3f,%.3f,%.6e,%.3e,%.6e,%.6e,%d\n", r == &corrected ? "corrected" : "uncorrected", s.clock, s.program_time, s.pass,
                    s.x, s.y, s.offset, s.offset_sd, s.distortion, s.error, s.learned ? 1 : 0);
      csv += line;
    }
  write_file_atomically(out / "path_samples.csv", csv);
  files.push_back("path_samples.csv");
}

void write_offset_stream(const std::filesystem::path& out, const online::LoopSimulationResult& corrected, std::vector<std::string>& files) {
  char line[512];
  std::string csv = "clock_s,believed_program_time_s,true_program_time_s,offset_mm\n";
  for (const auto& o : corrected.offsets) {
    std::snprintf(line, sizeof line, "%.3f,%.4f,%.4f,%.6e\n", o.clock, o.believed_time, o.true_time, o.offset);
    csv += line;
  }
  write_file_atomically(out / "offsets.csv", csv);
  files.push_back("offsets.csv");
}

// Final-shape predictions (with their band) against the truth, at the chosen passes and the last.
void write_final_shape_frames(const std::filesystem::path& out, const case_file::Case& c, const online::TruePart& truth,
                              const online::LoopSimulationResult& corrected, std::vector<std::string>& files) {
  std::vector<int> chosen = c.shape_vtk_passes;
  chosen.push_back(static_cast<int>(corrected.passes.size()));
  std::sort(chosen.begin(), chosen.end());
  chosen.erase(std::unique(chosen.begin(), chosen.end()), chosen.end());
  fem::PvdCollection pvd;
  for (int pass : chosen) {
    if (pass < 1 || pass > static_cast<int>(corrected.shapes.size())) continue;
    const auto& s = corrected.shapes[static_cast<std::size_t>(pass - 1)];
    fem::VtuFields f;
    const Eigen::Index n = s.nodes.cols();
    f.point_vectors.emplace_back("predicted_mm", Eigen::Map<const Eigen::VectorXd>(s.displacement.data(), 3 * n));
    f.point_vectors.emplace_back("true_mm", Eigen::Map<const Eigen::VectorXd>(truth.final_displacement.data(), 3 * n));
    std::vector<double> err(static_cast<std::size_t>(n)), sd(err.size()), inside(err.size());
    for (Eigen::Index i = 0; i < n; ++i) {
      const auto k = static_cast<std::size_t>(i);
      err[k] = s.displacement(2, i) - truth.final_displacement(2, i);
      sd[k] = s.sd(2, i);
      inside[k] = std::abs(err[k]) <= 1.96 * sd[k] ? 1 : 0;
    }
    f.point_scalars.emplace_back("vertical_error_mm", err);
    f.point_scalars.emplace_back("vertical_sd_mm", sd);
    f.point_scalars.emplace_back("inside_band95", inside);
    const std::string name = "final_shape_pass_" + std::to_string(pass) + ".vtu";
    fem::write_surface_vtu(out / name, s.nodes, s.faces, s.face_nodes, f);
    pvd.add(static_cast<double>(pass), name);
    files.push_back(name);
  }
  pvd.write(out / "final_shape.pvd");
  files.push_back("final_shape.pvd");
}

}  // namespace

machine::PostOptions post_options(const case_file::Case& c) {
  return {.title = c.name,
          .tool = c.program_tool_number,
          .tool_diameter = 2 * c.tool_radius,
          .spindle_speed = c.program_spindle_speed,
          .counter_clockwise = c.program_spindle == "ccw",
          .coolant = c.program_coolant == "flood" ? machine::Coolant::flood : c.program_coolant == "mist" ? machine::Coolant::mist : machine::Coolant::off,
          .clearance = c.program_clearance};
}

LoopOutputs write_loop_outputs(const std::filesystem::path& out, const case_file::Case& c, const reduce::LightModel& model, const online::TruePart& truth,
                               const online::LoopSimulationResult& corrected, const online::LoopSimulationResult& uncorrected) {
  LoopOutputs o;
  std::vector<std::string>& files = o.files;
  write_pass_table(out, c, corrected, uncorrected, files);
  write_shape_error_plot(out, c, corrected, files);
  write_path_samples(out, corrected, uncorrected, files);
  write_offset_stream(out, corrected, files);
  write_final_shape_frames(out, c, truth, corrected, files);
  const std::string program = corrected_gcode(model, online::floor_passes(model), corrected.offsets, post_options(c));
  if (!c.sync_machine.empty())
    o.program_verdict = machine::judge_program(program, "corrected_program.nc", machine::Kinematics(machine::load_machine(c.sync_machine)));
  if (!o.program_verdict || o.program_verdict->runnable()) {
    write_file_atomically(out / "corrected_program.nc", program);
    files.push_back("corrected_program.nc");
  }
  return o;
}

}  // namespace drom::loop
