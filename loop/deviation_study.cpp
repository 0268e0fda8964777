// drom deviation: learn the blank's geometric deviation from laser profiles during the approach and
// the first passes, and correct the tool's altitude (docs/design.md §8, seed chapter 2).
//   1. the deviation family on the area's grid and its POD basis (tolerance-bounded, reduce/pod.hpp);
//   2. the program: the approach waypoints, then one-way passes along x; edges at every waypoint;
//   3. offline, the scan extent needed (each mode in turn as the true surface);
//   4. online, the simulated blank scanned at the sensor's period, with its noise, calibration errors,
//      desynchronization and feed override; learning ends when the extent is reached and the recent
//      profiles are predicted within the tolerance; then the altitude is corrected;
//   5. error maps (VTK, PNG), error along the path (CSV, PNG), summary.json.
#include "loop/deviation_study.hpp"
#include "support/run_folder.hpp"
#include "support/summary.hpp"
#include "support/vtk_fields.hpp"
#include "online/dead_reckoning.hpp"
#include "online/deviation_learning.hpp"
#include "reduce/pod.hpp"
#include "support/atomic_file.hpp"
#include "support/input_error.hpp"
#include "support/png_plot.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>

namespace drom::loop {

namespace {

reduce::DeviationFamily build_family(const DeviationCase& c) {
  reduce::DeviationFamily family(c.grid);
  if (c.seed_a.count > 0) family.add_seed_parametric(c.seed_a, c.seed_b);
  if (c.bending_x.count > 0) family.add_bending('x', c.bending_x);
  if (c.bending_y.count > 0) family.add_bending('y', c.bending_y);
  if (c.twist.count > 0) family.add_twist(c.twist);
  if (c.offset.count > 0) family.add_offset(c.offset);
  if (c.tilt_x.count > 0) family.add_tilt('x', c.tilt_x);
  if (c.tilt_y.count > 0) family.add_tilt('y', c.tilt_y);
  for (const auto& m : c.measured) family.add_measured(m, c.nominal_z);
  if (family.size() == 0) throw InputError(c.origin + ": [family] has no member (every count is 0 and nothing is measured)");
  return family;
}

// The program: approach, then passes along x (cutting), each followed by a return to the next pass.
struct Program {
  Eigen::MatrixXd path;          // x, y, z, program time
  std::vector<char> cutting;     // per segment (i, i + 1)
  double cutting_start = 0;
};

Program build_program(const DeviationCase& c) {
  std::vector<Eigen::Vector2d> xy;
  std::vector<char> cut;
  for (std::size_t i = 0; i < c.approach_x.size(); ++i) {
    xy.emplace_back(c.approach_x[i], c.approach_y[i]);
    if (i > 0) cut.push_back(0);
  }
  const double y_first = c.grid.y0 + 0.5 * c.stepover;
  bool first = true;
  for (double y = y_first; y < c.grid.y1; y += c.stepover) {
    if (!first || (xy.back() - Eigen::Vector2d(c.grid.x0, y)).norm() > 1e-9) {
      xy.emplace_back(c.grid.x0, y);
      cut.push_back(0);
    }
    first = false;
    xy.emplace_back(c.grid.x1, y);
    cut.push_back(1);
  }
  Program p;
  p.path.resize(static_cast<Eigen::Index>(xy.size()), 4);
  double t = 0;
  for (std::size_t i = 0; i < xy.size(); ++i) {
    if (i > 0) t += (xy[i] - xy[i - 1]).norm() / c.feed;
    p.path.row(static_cast<Eigen::Index>(i)) << xy[i].x(), xy[i].y(), c.nominal_z, t;
  }
  p.cutting = cut;
  for (std::size_t i = 0; i < cut.size(); ++i)
    if (cut[i]) {
      p.cutting_start = p.path(static_cast<Eigen::Index>(i), 3);
      break;
    }
  return p;
}

bool cutting_at(const Program& p, double t) {
  for (Eigen::Index i = 0; i + 1 < p.path.rows(); ++i)
    if (t >= p.path(i, 3) && t <= p.path(i + 1, 3)) return p.cutting[static_cast<std::size_t>(i)] != 0;
  return false;
}

// The blank's true deviation on the area's grid (the seed's surface or a measured one), read between
// the grid's nodes by its interpolation weights.
struct TrueDeviation {
  const reduce::DeviationGrid& grid;
  Eigen::VectorXd values;
  double at(double x, double y) const {
    double v = 0;
    for (const auto& [i, w] : grid.weights(x, y)) v += w * values[i];
    return v;
  }
};

Eigen::VectorXd true_deviation_values(const DeviationCase& c) {
  const auto& grid = c.grid;
  Eigen::VectorXd truth_values(grid.size());
  if (c.truth == "seed") {
    for (int j = 0; j < grid.ny; ++j)
      for (int i = 0; i < grid.nx; ++i) truth_values[grid.index(i, j)] = reduce::seed_true_surface(grid.x(i), grid.y(j));
  } else {
    reduce::DeviationFamily measured(grid);
    measured.add_measured(c.truth_csv, c.nominal_z);
    truth_values = measured.snapshots().col(0);
  }
  return truth_values;
}

// Synchronization: an edge at every waypoint.
std::vector<int> every_waypoint(const Program& program) {
  std::vector<int> sync(static_cast<std::size_t>(program.path.rows()));
  for (std::size_t i = 0; i < sync.size(); ++i) sync[i] = static_cast<int>(i);
  return sync;
}

// 3. Offline: the scan extent, checked along the first pass.
online::ScanExtent scan_extent(const DeviationCase& c, const reduce::Pod& pod, const Program& program) {
  const auto& grid = c.grid;
  online::ScanPlan plan;
  plan.path = program.path;
  plan.period = c.period;
  plan.sheet = c.sheet;
  std::vector<Eigen::Vector2d> check;
  for (int k = 0; k <= 50; ++k) check.emplace_back(grid.x0 + (grid.x1 - grid.x0) * k / 50.0, grid.y0 + 0.5 * c.stepover);
  Eigen::VectorXd amplitude(pod.rank());
  for (int k = 0; k < pod.rank(); ++k) amplitude[k] = pod.singular_values[k] * pod.right.col(k).cwiseAbs().maxCoeff();
  const double program_end = program.path(program.path.rows() - 1, 3);
  return online::needed_scan_extent(grid, pod.modes, amplitude, plan, program_end, c.learning_tolerance, check);
}

// What the online stage is run on.
struct LearningRun {
  const DeviationCase& c;
  const reduce::Pod& pod;
  const Program& program;
  const std::vector<int>& sync;
  online::DeadReckoning& reckoning;
  const TrueDeviation& truth;
  double extent_time = 0;  // the program time the scan must reach before learning may end
};

// What it gives: the altitude error under the tool along the path, with and without correction, and
// the identification when learning ended and at the end.
struct Learning {
  std::string csv;  // error_along_path.csv
  PlotSeries corrected{"with correction (after learning)", {}, {}, "-"}, uncorrected{"without correction", {}, {}, "-"};
  double learned_at = -1, worst_corrected = 0, worst_uncorrected = 0;
  Eigen::VectorXd at_learning;  // the coefficients when learning ended; empty: it never did
  Eigen::VectorXd final_coefficients;
  long long profiles = 0, points_used = 0;
};

// 4. Online: the blank scanned at the sensor's period; the altitude corrected once learned.
Learning learn_and_correct(const LearningRun& run) {
  const DeviationCase& c = run.c;
  const auto& grid = c.grid;
  const Program& program = run.program;
  const std::vector<int>& sync = run.sync;
  const double program_end = program.path(program.path.rows() - 1, 3);
  const online::HeightField surface = [&](double x, double y) -> std::optional<double> {
    if (!grid.contains(x, y)) return std::nullopt;
    return c.nominal_z + run.truth.at(x, y);
  };
  online::DeviationIdentifier id(grid, run.pod.modes, c.nominal_z);
  online::LearningMonitor monitor(c.learning_tolerance, c.errors.noise_sd, c.learning_window);
  std::mt19937 rng(20150101);
  std::size_t next_edge = 0;
  Learning l;
  l.csv = "clock_s,program_time_s,x_mm,y_mm,cutting,learned,true_deviation_mm,correction_mm,error_corrected_mm,error_uncorrected_mm\n";
  for (long step = 0;; ++step) {
    const double clock = static_cast<double>(step) * c.period, t_true = clock * c.feed_override;
    if (t_true > program_end) break;
    // Edges arrive when the machine (at its actual feed) passes a waypoint, late by the desync.
    while (next_edge < sync.size() && program.path(sync[next_edge], 3) / c.feed_override + c.desync <= clock) {
      run.reckoning.edge(sync[next_edge], program.path(sync[next_edge], 3) / c.feed_override + c.desync);
      ++next_edge;
    }
    const Eigen::Vector3d tip = run.reckoning.position_at_program_time(t_true), believed = run.reckoning.position(clock);
    const bool cutting = cutting_at(program, t_true) && grid.contains(tip.x(), tip.y());
    const double d = run.truth.at(tip.x(), tip.y());
    double correction = 0;
    if (l.learned_at >= 0 && grid.contains(believed.x(), believed.y())) correction = id.deviation(believed.x(), believed.y(), id.coefficients());
    if (cutting) {
      l.uncorrected.x.push_back(t_true), l.uncorrected.y.push_back(std::abs(d));
      l.worst_uncorrected = std::max(l.worst_uncorrected, std::abs(d));
      if (l.learned_at >= 0) {
        l.corrected.x.push_back(t_true), l.corrected.y.push_back(std::abs(correction - d));
        l.worst_corrected = std::max(l.worst_corrected, std::abs(correction - d));
      }
    }
    char line[256];
    const bool learned = l.learned_at >= 0;
    std::snprintf(line, sizeof line, "%.3f,%.3f,%.4f,%.4f,%d,%d,%.6e,%.6e,%.6e,%.6e\n", clock, t_true, tip.x(), tip.y(), cutting ? 1 : 0,
                  learned ? 1 : 0, d, correction, learned && cutting ? correction - d : std::nan(""), cutting ? -d : std::nan(""));
    l.csv += line;
    monitor.add(id, online::scan(c.sheet, c.errors, believed, tip, surface, rng));
    ++l.profiles;
    if (l.learned_at < 0 && monitor.learned() && run.reckoning.program_time(clock) >= run.extent_time) {
      l.learned_at = t_true;
      l.at_learning = id.coefficients();
    }
  }
  l.final_coefficients = id.coefficients();
  l.points_used = id.points();
  return l;
}

void write_error_along_path(const DeviationCase& c, const std::filesystem::path& out, const Learning& l) {
  write_file_atomically(out / "error_along_path.csv", l.csv);
  PlotSpec along;
  along.title = c.name + ": altitude error under the tool on cutting moves";
  along.x_label = "program time (s)";
  along.y_label = "|error| (mm)";
  along.series = {l.uncorrected, l.corrected};
  along.hlines = {{"path tolerance", c.path_tolerance}};
  along.log_y = true;
  write_png_plot(out / "error_along_path.png", along);
}

struct IdentificationErrors {
  double max_end = 0, max_learn = 0;  // mm, over the grid
};

// 5. Error maps: the identification at the end of learning and at the end, against the truth.
IdentificationErrors write_error_maps(const DeviationCase& c, const std::filesystem::path& out, const reduce::Pod& pod, const Program& program,
                                      const Eigen::VectorXd& truth_values, const Learning& l) {
  const auto& grid = c.grid;
  const Eigen::VectorXd& final_c = l.final_coefficients;
  const Eigen::VectorXd& at_learning = l.at_learning;
  std::vector<double> true_v(static_cast<std::size_t>(grid.size())), end_v(true_v.size()), end_e(true_v.size()), learn_v(true_v.size(), std::nan("")),
      learn_e(true_v.size(), std::nan(""));
  IdentificationErrors e;
  for (int k = 0; k < grid.size(); ++k) {
    const auto ku = static_cast<std::size_t>(k);
    true_v[ku] = truth_values[k];
    end_v[ku] = pod.modes.row(k).dot(final_c);
    end_e[ku] = end_v[ku] - true_v[ku];
    e.max_end = std::max(e.max_end, std::abs(end_e[ku]));
    if (at_learning.size() > 0) {
      learn_v[ku] = pod.modes.row(k).dot(at_learning);
      learn_e[ku] = learn_v[ku] - true_v[ku];
      e.max_learn = std::max(e.max_learn, std::abs(learn_e[ku]));
    }
  }
  Eigen::Matrix3Xd nodes(3, grid.size());
  for (int j = 0; j < grid.ny; ++j)
    for (int i = 0; i < grid.nx; ++i) nodes.col(grid.index(i, j)) = Eigen::Vector3d(grid.x(i), grid.y(j), c.nominal_z);
  std::vector<int> quads;
  for (int j = 0; j + 1 < grid.ny; ++j)
    for (int i = 0; i + 1 < grid.nx; ++i)
      for (int v : {grid.index(i, j), grid.index(i + 1, j), grid.index(i + 1, j + 1), grid.index(i, j + 1)}) quads.push_back(v);
  VtuFields fields;
  fields.point_scalars = {{"true_deviation_mm", true_v}, {"identified_end_mm", end_v}, {"error_end_mm", end_e}, {"identified_at_learning_mm", learn_v},
                          {"error_at_learning_mm", learn_e}};
  write_surface_vtu(out / "error_map.vtu", nodes, quads, 4, fields);
  PlotSpec map;
  map.title = c.name + ": identification error at the end of learning";
  map.x_label = "x (mm)";
  map.y_label = "y (mm)";
  map.map = PlotMap{grid.x0, grid.x1, grid.y0, grid.y1, grid.nx, grid.ny, at_learning.size() > 0 ? learn_e : end_e, "identified - true (mm)", "coolwarm"};
  PlotSeries path_xy{"program", {}, {}, "k-"};
  for (Eigen::Index i = 0; i < program.path.rows(); ++i) path_xy.x.push_back(program.path(i, 0)), path_xy.y.push_back(program.path(i, 1));
  map.series = {path_xy};
  write_png_plot(out / "error_map.png", map);
  return e;
}

// Everything summary.json reports.
struct StudyFigures {
  const DeviationCase& c;
  int family_members = 0;
  const reduce::Pod& pod;
  const online::ScanExtent& extent;
  const Program& program;
  const Learning& learning;
  IdentificationErrors errors;
};

nlohmann::json deviation_summary(const StudyFigures& f, double seconds) {
  const DeviationCase& c = f.c;
  const online::ScanExtent& extent = f.extent;
  const Learning& l = f.learning;
  const double extent_length = std::isfinite(extent.program_time) ? extent.program_time * c.feed : -1;
  std::vector<double> per_mode;  // -1: that mode is never identified within the tolerance on this program
  for (double t : extent.per_mode_time) per_mode.push_back(std::isfinite(t) ? t : -1.0);
  return {{"command", "deviation"},
          {"case", c.name},
          {"family_members", f.family_members},
          {"rank", f.pod.rank()},
          {"pod_max_bound_mm", f.pod.max_bound},
          {"scan_extent_program_time_s", std::isfinite(extent.program_time) ? extent.program_time : -1.0},
          {"scan_extent_path_mm", extent_length},
          {"scan_extent_per_mode_s", per_mode},
          {"cutting_starts_s", f.program.cutting_start},
          {"learned_at_program_time_s", l.learned_at},
          {"profiles", l.profiles},
          {"points_used", l.points_used},
          {"max_error_corrected_mm", l.learned_at >= 0 ? l.worst_corrected : -1.0},
          {"max_error_uncorrected_mm", l.worst_uncorrected},
          {"path_tolerance_mm", c.path_tolerance},
          {"within_path_tolerance", l.learned_at >= 0 && l.worst_corrected <= c.path_tolerance},
          {"identification_max_error_at_learning_mm", l.at_learning.size() > 0 ? f.errors.max_learn : -1.0},
          {"identification_max_error_end_mm", f.errors.max_end},
          {"sensor", {{"angle_deg", c.sheet.angle_deg}, {"noise_mm", c.errors.noise_sd}, {"offset_error_mm", {c.errors.offset_error.x(), c.errors.offset_error.y(), c.errors.offset_error.z()}},
                      {"angle_error_deg", c.errors.angle_error_deg}, {"desync_s", c.desync}, {"feed_override", c.feed_override}}},
          {"time_s", seconds},
          {"machine", machine_info()},
          {"files", {"error_along_path.csv", "error_along_path.png", "error_map.vtu", "error_map.png", "summary.json"}}};
}

}  // namespace

nlohmann::json run_deviation_study(const DeviationCase& c, const std::filesystem::path& out, bool quiet) {
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  check_output_folder(out);
  clear_earlier_run(out, "deviation");

  // 1. Family and basis.
  const reduce::DeviationFamily family = build_family(c);
  const reduce::Pod pod = reduce::truncated_pod(family.snapshots(), c.family_tolerance);
  const TrueDeviation truth{.grid = c.grid, .values = true_deviation_values(c)};

  // 2. Program and synchronization.
  const Program program = build_program(c);
  const std::vector<int> sync = every_waypoint(program);
  online::DeadReckoning reckoning(program.path, sync);

  const online::ScanExtent extent = scan_extent(c, pod, program);
  if (!quiet)
    std::fprintf(stderr, "drom deviation: %d family members, r = %d modes (bound %.2g mm); scan extent needed: %.1f s of program\n", family.size(), pod.rank(),
                 pod.max_bound, extent.program_time);
  const Learning learning = learn_and_correct(
      {.c = c, .pod = pod, .program = program, .sync = sync, .reckoning = reckoning, .truth = truth, .extent_time = extent.program_time});
  write_error_along_path(c, out, learning);
  const IdentificationErrors errors = write_error_maps(c, out, pod, program, truth.values, learning);

  const nlohmann::json summary = deviation_summary(
      {.c = c, .family_members = family.size(), .pod = pod, .extent = extent, .program = program, .learning = learning, .errors = errors}, elapsed());
  write_summary(out, summary);
  return summary;
}

}  // namespace drom::loop
