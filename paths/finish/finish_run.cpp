#include "paths/finish/finish_run.hpp"

#include "paths/finish/finish_outputs.hpp"
#include "paths/finish/plane_model.hpp"
#include "paths/finish/scallop_check.hpp"
#include "machine/feed_prediction.hpp"
#include "machine/post_processor.hpp"
#include "support/atomic_file.hpp"
#include "support/input_error.hpp"
#include "support/png_plot.hpp"
#include "support/summary.hpp"
#include "support/version.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <functional>
#include <mutex>
#include <numbers>
#include <sstream>
#include <thread>

namespace drom::paths {

namespace {

constexpr double kDeg = 180 / std::numbers::pi;
using nlohmann::json;

json setup_json(const ZoneSetup& s) {
  json j;
  j["azimuth_deg"] = s.azimuth * kDeg;
  j["zeta_deg"] = s.zeta * kDeg;
  j["centre"] = {s.centre.x(), s.centre.y(), s.centre.z()};
  std::vector<double> r(s.rotation.data(), s.rotation.data() + 9);
  j["rotation"] = r;
  const Eigen::Vector3d a = s.axis();
  j["tool_axis"] = {a.x(), a.y(), a.z()};
  return j;
}

ZoneSetup setup_from_json(const json& j) {
  ZoneSetup s;
  s.azimuth = j.at("azimuth_deg").get<double>() / kDeg;
  s.zeta = j.at("zeta_deg").get<double>() / kDeg;
  const auto c = j.at("centre").get<std::vector<double>>();
  s.centre = Eigen::Vector3d(c[0], c[1], c[2]);
  const auto r = j.at("rotation").get<std::vector<double>>();
  s.rotation = Eigen::Map<const Eigen::Matrix3d>(r.data());
  return s;
}

json optimum_json(const KOptimum& k, const std::string& fingerprint) {
  json j;
  j["fingerprint"] = fingerprint;
  j["clusters"] = k.clusters;
  j["zones"] = k.zones.count();
  j["start_time_s"] = k.start_time;
  j["best_time_s"] = k.best_time;
  j["gain"] = k.gain();
  j["weights"] = {k.weights(0), k.weights(1), k.weights(2), k.weights(3)};
  j["black_box_equivalents"] = k.spent;
  j["partitions_evaluated"] = k.evaluations;
  j["history"] = k.history;
  for (const auto& s : k.setups) j["setups"].push_back(setup_json(s));
  return j;
}

// The optimum stored by an earlier run of the same case, its zones recomputed (K-means is deterministic).
bool load_optimum(const std::filesystem::path& file, const std::string& fingerprint, const FinishingProblem& problem, KOptimum& k) {
  std::ifstream in(file);
  if (!in) return false;
  try {
    const json j = json::parse(in);
    if (j.at("fingerprint").get<std::string>() != fingerprint) return false;
    k.clusters = j.at("clusters").get<int>();
    k.start_time = j.at("start_time_s").get<double>();
    k.best_time = j.at("best_time_s").get<double>();
    const auto w = j.at("weights").get<std::vector<double>>();
    k.weights = Eigen::Vector4d(w[0], w[1], w[2], w[3]);
    k.spent = j.at("black_box_equivalents").get<double>();
    k.evaluations = j.at("partitions_evaluated").get<int>();
    k.history = j.at("history").get<std::vector<std::pair<double, double>>>();
    ClusteringSettings cs;
    cs.weights = k.weights;
    k.zones = connected_zones(kmeans(problem.samples, problem.surface, k.clusters, cs), problem.samples.cells_u, problem.samples.cells_v);
    k.setups.clear();
    for (const auto& s : j.at("setups")) k.setups.push_back(setup_from_json(s));
    return static_cast<int>(k.setups.size()) == k.zones.count();
  } catch (const std::exception&) {
    return false;
  }
}

std::vector<int> all_samples(const SurfaceSamples& s) {
  std::vector<int> out;
  for (int i = 0; i < s.size(); ++i)
    if (s.inside[static_cast<std::size_t>(i)]) out.push_back(i);
  return out;
}

}  // namespace

json run_finish(const FinishCase& c, const FinishRunOptions& o) {
  const auto started = std::chrono::steady_clock::now();
  std::filesystem::create_directories(o.out);
  const auto say = [&](const std::string& line) {
    if (!o.quiet) std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  };
  const geometry::NurbsSurface& surface = c.surface.surface;

  // The surface described, and the tool chosen (§2.4.1).
  FinishingSettings search_settings = c.settings;
  search_settings.exact = false;  // the fast variant inside the search; the output path below is the case's
  FinishingProblem problem = make_problem(surface, c.surface.trim, search_settings, c.samples, c.mesh_step);
  std::vector<Eigen::Vector3d> points, normals;
  for (const int i : all_samples(problem.samples)) {
    points.push_back(problem.samples.points[static_cast<std::size_t>(i)]);
    normals.push_back(problem.samples.normals[static_cast<std::size_t>(i)]);
  }
  const PcaPlane plane = pca_plane(points);
  const ToolVerdict verdict = choose_tool(plane, c.torus, c.ball, c.settings.scallop, c.settings.timer.cutting());
  FinishingSettings settings = c.settings;
  if (c.auto_tool) settings.tool = verdict.ball ? c.ball : c.torus;
  problem.settings.tool = settings.tool;
  say("drom finish: " + c.name + " (" + c.surface.description + "), " + settings.tool.name() + ", sh " + std::to_string(settings.scallop) + " mm");
  say("  verdict: " + verdict.reason);

  // Zoning and setups.
  Zones zones;
  std::vector<ZoneSetup> setups;
  std::vector<KOptimum> optima;
  const std::string fingerprint = std::to_string(std::hash<std::string>{}(c.resolved_toml + kVersion));
  const bool ball = settings.tool.kind == ToolKind::ball;
  if (c.orientation) {
    zones.zone.assign(static_cast<std::size_t>(problem.samples.size()), -1);
    for (const int i : all_samples(problem.samples)) zones.zone[static_cast<std::size_t>(i)] = 0;
    zones.cluster = {0};
    const ZoneSetup tilt = tilted_setup((*c.orientation)(0), (*c.orientation)(1), 0, plane.mean);
    std::vector<Eigen::Vector3d> turned_points;
    for (const auto& q : points) turned_points.push_back(tilt.to_machine(q));
    const PcaPlane turned = pca_plane(turned_points);
    const double azimuth = ball ? turned.principal_azimuth : machine_steepest_azimuth(problem.samples, all_samples(problem.samples), tilt.rotation);
    setups = {tilted_setup((*c.orientation)(0), (*c.orientation)(1), azimuth, plane.mean)};
    say("  fixed orientation: one zone, tool axis at " + std::to_string((*c.orientation)(0) * kDeg) + " deg from Z");
  } else if (c.optimize) {
    const std::filesystem::path dir = o.out / "optimization";
    std::filesystem::create_directories(dir);
    OptimizerSettings os;
    os.mode = c.setup;
    os.budget = c.budget;
    os.surrogate = c.surrogate;
    std::vector<int> ks;
    for (int k = c.clusters_min; k <= c.clusters_max; ++k) ks.push_back(k);
    optima.resize(ks.size());
    std::atomic<std::size_t> next{0};
    std::mutex print;
    const auto work = [&] {
      for (std::size_t i; (i = next++) < ks.size();) {
        std::ostringstream name;
        name << 'K' << ks[i] << ".json";
        const std::filesystem::path file = dir / name.str();
        KOptimum k;
        bool resumed = load_optimum(file, fingerprint, problem, k);
        const auto t0 = std::chrono::steady_clock::now();
        if (!resumed) {
          k = optimize_clusters(problem, ks[i], os);
          write_file_atomically(file, optimum_json(k, fingerprint).dump(1));
        }
        const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        std::ostringstream line;
        line.precision(4);
        line << "  K = " << ks[i] << ": " << k.zones.count() << " zones, f0 " << k.start_time << " s -> f* " << k.best_time << " s (gain " << 100 * k.gain()
             << " %), " << static_cast<int>(k.spent) << " black-box equivalents";
        if (resumed) line << " (kept from an earlier run)";
        else line << ", " << seconds << " s";
        {
          std::lock_guard<std::mutex> lock(print);
          say(line.str());
        }
        optima[i] = std::move(k);
      }
    };
    const int threads = std::max(1, std::min<int>(static_cast<int>(ks.size()), o.threads > 0 ? o.threads : static_cast<int>(std::thread::hardware_concurrency())));
    std::vector<std::thread> pool;
    for (int t = 1; t < threads; ++t) pool.emplace_back(work);
    work();
    for (auto& t : pool) t.join();
    const auto best = std::min_element(optima.begin(), optima.end(), [](const KOptimum& a, const KOptimum& b) { return a.best_time < b.best_time; });
    zones = best->zones;
    setups = best->setups;
  } else {
    const int k = c.clusters_min;
    std::vector<int> labels;
    if (c.algorithm == "kmeans") labels = kmeans(problem.samples, surface, k, c.clustering);
    else if (c.algorithm == "rpcl") {
      RpclSettings r;
      r.seed = c.rpcl_seed;
      labels = rpcl(problem.samples, surface, k, c.clustering, r);
    } else labels = ward(problem.samples, k, c.clustering.weights);
    zones = connected_zones(labels, problem.samples.cells_u, problem.samples.cells_v);
    const auto shapes = describe_zones(problem.samples, zones);
    for (const auto& s : shapes) setups.push_back(three_axis_setup(ball ? s.plane.principal_azimuth : s.steepest_azimuth));
  }

  // The output path: the case's variant, ordered, timed.
  const FinishingPlan plan = plan_finishing(problem.mesh, zones, setups, settings);
  std::ostringstream totals;
  totals.precision(4);
  totals << "  finish: " << zones.count() << " zones, " << plan.pass_count() << " passes, " << plan.time() << " s (passes " << plan.pass_time() << ", links "
         << plan.link_time() << ", retracts " << plan.retract_time() << ", between zones " << plan.move_time << "), " << plan.length() << " mm";
  say(totals.str());
  const int gouges = plan.gouging_contacts();
  std::string gouge_note;
  if (gouges > 0) {
    Eigen::Vector3d at = Eigen::Vector3d::Zero();
    for (const auto& z : plan.zones) {
      const auto p = std::find_if(z.passes.begin(), z.passes.end(), [](const Pass& q) { return q.gouging_contacts > 0; });
      if (p != z.passes.end()) {
        at = p->first_gouge;
        break;
      }
    }
    std::ostringstream msg;
    msg.precision(4);
    msg << "the " << settings.tool.name() << " gouges the surface at " << gouges << " contact points, the first at (" << at.transpose()
        << ") mm: the ground across the passes is more concave than the tool's trace there";
    // A tool axis the user fixed is theirs to change; a setup drom chose is reported, loudly.
    if (c.orientation) throw InputError(c.orientation_where + ": " + msg.str() + "; tilt the axis less, or use a ball or a smaller corner radius");
    gouge_note = msg.str() + " (a smaller tool, or a ball, avoids it)";
    say("  WARNING: " + gouge_note);
  }
  const ScallopCheck check = check_scallop(surface, plan.zones, settings.tool, 0, 1, 0, 1, 40, 40);

  // Files.
  std::vector<std::string> files = {"zones.vtu", "paths.vtp", "cl.csv", "breakdown.csv"};
  write_zone_map(o.out / "zones.vtu", surface, problem.samples, zones);
  write_pass_polylines(o.out / "paths.vtp", plan, settings.tool);
  write_cl_csv(o.out / "cl.csv", plan, settings.tool);
  write_breakdown_csv(o.out / "breakdown.csv", plan);
  // The program: machine/'s inverse kinematics, feed predictor and post-processor on the case's machine.
  std::string program_note;
  double predicted = -1;
  try {
    const machine::Machine m = machine::load_machine(c.machine_definition);
    const machine::Kinematics kinematics(m);
    const machine::ClProgram cl = cl_program(plan, settings.tool, settings.timer.cutting().feed * 60, settings.clearance, settings.approach);
    const machine::ClOnMachine on = machine::cl_to_machine_program(cl, kinematics);
    if (!on.joints.violations.empty()) {
      program_note = "no program: on " + m.name + ", " + on.joints.violations.front().what;
    } else {
      predicted = machine::predict_feed(on.program, kinematics).cycle_time;
      write_file_atomically(o.out / "program.ngc", machine::post_process(cl, kinematics, {"drom finish " + c.name}));
      files.push_back("program.ngc");
      std::ostringstream line;
      line.precision(4);
      line << "  program for " << m.name << ": cycle time " << predicted << " s predicted by machine/ (junctions, per-axis limits, rapids)";
      say(line.str());
    }
  } catch (const InputError& e) {
    program_note = std::string("no program: ") + e.what();
  }
  if (!program_note.empty()) say("  " + program_note);
  if (!optima.empty()) {
    std::ostringstream csv;
    csv << "clusters,black_box_equivalents,best_time_s\n";
    PlotSpec plot;
    plot.title = c.name + ": optimisation history";
    plot.x_label = "black-box evaluations (equivalents)";
    plot.y_label = "best finishing time (s)";
    for (const auto& k : optima) {
      PlotSeries series;
      series.name = "K = " + std::to_string(k.clusters);
      for (const auto& [x, y] : k.history) {
        csv << k.clusters << ',' << x << ',' << y << '\n';
        series.x.push_back(x);
        series.y.push_back(y);
      }
      plot.series.push_back(series);
    }
    write_file_atomically(o.out / "history.csv", csv.str());
    files.push_back("history.csv");
    if (write_png_plot(o.out / "history.png", plot)) files.push_back("history.png");
  }

  json s;
  s["command"] = "drom finish";
  s["case"] = c.name;
  s["surface"] = c.surface.description;
  s["tool"] = settings.tool.name();
  s["scallop_mm"] = settings.scallop;
  s["stepover_model"] = settings.stepover == StepoverModel::curved ? "curved" : settings.stepover == StepoverModel::flat ? "flat" : "seed";
  s["variant"] = settings.exact ? "exact" : "fast";
  s["accounting"] = settings.accounting == Accounting::machine ? "machine" : "seed";
  s["time_model"] = "search: machine/'s double S per move; program: machine/'s feed predictor";
  s["machine"] = c.machine_definition;
  if (predicted >= 0) s["predicted_cycle_time_s"] = predicted;
  s["pca"] = {{"lambda", {plane.lambda(0), plane.lambda(1), plane.lambda(2)}},
              {"shape_factor", plane.shape_factor},
              {"size_mm2", plane.size},
              {"slope_deg", plane.slope * kDeg},
              {"mean_local_slope_deg", mean_slope(normals) * kDeg},
              {"principal_azimuth_deg", plane.principal_azimuth * kDeg},
              {"steepest_azimuth_deg", plane.steepest_azimuth * kDeg},
              {"width_mm", plane.width},
              {"height_mm", plane.height}};
  s["verdict"] = {{"tool", verdict.ball ? "ball along the principal direction" : "torus along the steepest slope"},
                  {"critical_slope_deg", verdict.critical_slope * kDeg},
                  {"critical_shape_factor", verdict.critical_shape},
                  {"plane_time_torus_s", verdict.torus.time},
                  {"plane_time_ball_s", verdict.ball_time.time},
                  {"reason", verdict.reason}};
  s["zones"] = zones.count();
  s["time_s"] = {{"total", plan.time()}, {"passes", plan.pass_time()}, {"links", plan.link_time()}, {"retracts", plan.retract_time()}, {"between_zones", plan.move_time}};
  s["length_mm"] = {{"total", plan.length()}, {"passes", plan.pass_length()}, {"links", plan.link_length()}};
  s["passes"] = plan.pass_count();
  double run_outs = 0;
  for (const auto& z : plan.zones)
    for (const auto& p : z.passes) run_outs += p.run_out_length;
  s["run_out"] = {{"longest_mm", settings.run_out}, {"contact_length_mm", run_outs}};
  s["gouging_contacts"] = gouges;
  if (!gouge_note.empty()) s["gouge_warning"] = gouge_note;
  s["scallop_check"] = {{"points", check.points}, {"max_height_mm", check.max_height}, {"max_gouge_mm", check.max_gouge}, {"worst_uv", {check.worst_uv.x(), check.worst_uv.y()}}, {"grid", "40 x 40 over the surface"}};
  for (const auto& k : optima)
    s["optimization"].push_back({{"clusters", k.clusters}, {"zones", k.zones.count()}, {"f0_s", k.start_time}, {"f_star_s", k.best_time}, {"gain", k.gain()},
                                 {"black_box_equivalents", k.spent}});
  if (!program_note.empty()) s["program"] = program_note;
  s["files"] = files;
  s["elapsed_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  s["version"] = kVersion;
  write_summary(o.out, s);
  return s;
}

}  // namespace drom::paths
