#include "paths/finish/finish_run.hpp"

#include "paths/finish/finish_outputs.hpp"
#include "paths/cutter/stepover.hpp"
#include "paths/finish/length_bound.hpp"
#include "paths/finish/plane_model.hpp"
#include "paths/finish/scallop_check.hpp"
#include "machine/feed_prediction.hpp"
#include "machine/post_processor.hpp"
#include "machine/program_verdict.hpp"
#include "support/atomic_file.hpp"
#include "support/input_error.hpp"
#include "support/png_plot.hpp"
#include "support/run_folder.hpp"
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

using Say = std::function<void(const std::string&)>;

// Stage 1's result: the surface sampled, its PCA plane, and the tool the verdict (or the case) chose.
struct Described {
  FinishingProblem problem;
  std::vector<Eigen::Vector3d> points, normals;  // the samples inside the trim
  PcaPlane plane;
  ToolVerdict verdict;
  FinishingSettings settings;  // the case's, with the chosen tool
};

// Stage 2's result.
struct Zoning {
  Zones zones;
  std::vector<ZoneSetup> setups;
  std::vector<KOptimum> optima;  // one per K when the zoning was optimised
};

// Stage 1 (§2.4.1): the surface described, and the tool chosen.
Described describe_surface(const FinishCase& c, const Say& say) {
  FinishingSettings search_settings = c.settings;
  search_settings.exact = false;  // the fast variant inside the search; the output path is the case's
  Described d{make_problem(c.surface.surface, c.surface.trim, search_settings, c.samples, c.mesh_step), {}, {}, {}, {}, c.settings};
  for (const int i : all_samples(d.problem.samples)) {
    d.points.push_back(d.problem.samples.points[static_cast<std::size_t>(i)]);
    d.normals.push_back(d.problem.samples.normals[static_cast<std::size_t>(i)]);
  }
  d.plane = pca_plane(d.points);
  d.verdict = choose_tool(d.plane, c.torus, c.ball, c.settings.scallop, c.settings.timer.cutting());
  if (c.auto_tool) d.settings.tool = d.verdict.ball ? c.ball : c.torus;
  d.problem.settings.tool = d.settings.tool;
  say("drom finish: " + c.name + " (" + c.surface.description + "), " + d.settings.tool.name() + ", sh " + std::to_string(d.settings.scallop) + " mm");
  say("  verdict: " + d.verdict.reason);
  return d;
}

// Stage 2, a fixed tool axis: one zone, 3+2 along the case's orientation.
Zoning zone_at_fixed_orientation(const FinishCase& c, const Described& d, const Say& say) {
  const SurfaceSamples& samples = d.problem.samples;
  Zoning z;
  z.zones.zone.assign(static_cast<std::size_t>(samples.size()), -1);
  for (const int i : all_samples(samples)) z.zones.zone[static_cast<std::size_t>(i)] = 0;
  z.zones.cluster = {0};
  const ZoneSetup tilt = tilted_setup((*c.orientation)(0), (*c.orientation)(1), 0, d.plane.mean);
  std::vector<Eigen::Vector3d> turned_points;
  for (const auto& q : d.points) turned_points.push_back(tilt.to_machine(q));
  const PcaPlane turned = pca_plane(turned_points);
  const bool ball = d.settings.tool.kind == ToolKind::ball;
  const double azimuth = ball ? turned.principal_azimuth : machine_steepest_azimuth(samples, all_samples(samples), tilt.rotation);
  z.setups = {tilted_setup((*c.orientation)(0), (*c.orientation)(1), azimuth, d.plane.mean)};
  say("  fixed orientation: one zone, tool axis at " + std::to_string((*c.orientation)(0) * kDeg) + " deg from Z");
  return z;
}

// One K's optimum: kept from an earlier run of the same case, or searched and stored atomically.
KOptimum optimize_one_k(const FinishingProblem& problem, int clusters, const OptimizerSettings& os, const std::filesystem::path& dir,
                        const std::string& fingerprint, std::mutex& print, const Say& say) {
  std::ostringstream name;
  name << 'K' << clusters << ".json";
  const std::filesystem::path file = dir / name.str();
  KOptimum k;
  bool resumed = load_optimum(file, fingerprint, problem, k);
  const auto t0 = std::chrono::steady_clock::now();
  if (!resumed) {
    k = optimize_clusters(problem, clusters, os);
    write_file_atomically(file, optimum_json(k, fingerprint).dump(1));
  }
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::ostringstream line;
  line.precision(4);
  line << "  K = " << clusters << ": " << k.zones.count() << " zones, f0 " << k.start_time << " s -> f* " << k.best_time << " s (gain " << 100 * k.gain()
       << " %), " << static_cast<int>(k.spent) << " black-box equivalents";
  if (resumed) line << " (kept from an earlier run)";
  else line << ", " << seconds << " s";
  {
    std::lock_guard<std::mutex> lock(print);
    say(line.str());
  }
  return k;
}

// Stage 2, optimised (the seed's ch. 4): every K in the case's range, in parallel, the best kept.
Zoning zone_by_optimization(const FinishCase& c, const FinishRunOptions& o, const Described& d, const Say& say) {
  const std::filesystem::path dir = o.out / "optimization";
  std::filesystem::create_directories(dir);
  const OptimizerSettings os{.mode = c.setup, .budget = c.budget, .surrogate = c.surrogate};
  const std::string fingerprint = std::to_string(std::hash<std::string>{}(c.resolved_toml + kVersion));
  std::vector<int> ks;
  for (int k = c.clusters_min; k <= c.clusters_max; ++k) ks.push_back(k);
  Zoning z;
  z.optima.resize(ks.size());
  std::atomic<std::size_t> next{0};
  std::mutex print;
  const auto work = [&] {
    for (std::size_t i; (i = next++) < ks.size();) z.optima[i] = optimize_one_k(d.problem, ks[i], os, dir, fingerprint, print, say);
  };
  const int threads = std::max(1, std::min<int>(static_cast<int>(ks.size()), o.threads > 0 ? o.threads : static_cast<int>(std::thread::hardware_concurrency())));
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(work);
  work();
  for (auto& t : pool) t.join();
  const auto best = std::min_element(z.optima.begin(), z.optima.end(), [](const KOptimum& a, const KOptimum& b) { return a.best_time < b.best_time; });
  z.zones = best->zones;
  z.setups = best->setups;
  return z;
}

// Stage 2, one partition: the case's clustering at K = clusters_min, each zone 3-axis.
Zoning zone_by_clustering(const FinishCase& c, const Described& d) {
  const SurfaceSamples& samples = d.problem.samples;
  const int k = c.clusters_min;
  std::vector<int> labels;
  if (c.algorithm == "kmeans") labels = kmeans(samples, c.surface.surface, k, c.clustering);
  else if (c.algorithm == "rpcl") {
    RpclSettings r;
    r.seed = c.rpcl_seed;
    labels = rpcl(samples, c.surface.surface, k, c.clustering, r);
  } else labels = ward(samples, k, c.clustering.weights);
  Zoning z;
  z.zones = connected_zones(labels, samples.cells_u, samples.cells_v);
  const bool ball = d.settings.tool.kind == ToolKind::ball;
  for (const auto& s : describe_zones(samples, z.zones)) z.setups.push_back(three_axis_setup(ball ? s.plane.principal_azimuth : s.steepest_azimuth));
  return z;
}

Zoning zone_surface(const FinishCase& c, const FinishRunOptions& o, const Described& d, const Say& say) {
  if (c.orientation) return zone_at_fixed_orientation(c, d, say);
  if (c.optimize) return zone_by_optimization(c, o, d, say);
  return zone_by_clustering(c, d);
}

// Stage 3: the output path, the case's variant, ordered and timed.
FinishingPlan finish_zones(const Described& d, const Zoning& z, const Say& say) {
  FinishingPlan plan = plan_finishing(d.problem.mesh, z.zones, z.setups, d.settings);
  std::ostringstream totals;
  totals.precision(4);
  totals << "  finish: " << z.zones.count() << " zones, " << plan.pass_count() << " passes, " << plan.time() << " s (passes " << plan.pass_time() << ", links "
         << plan.link_time() << ", retracts " << plan.retract_time() << ", between zones " << plan.move_time << "), " << plan.length() << " mm";
  say(totals.str());
  return plan;
}

// Stage 4: contacts where the ground is more concave than the tool's trace. Refused where the user
// fixed the axis (theirs to change); reported, loudly, where drom chose the setup. Returns the note.
std::string report_gouges(const FinishCase& c, const FinishingPlan& plan, const Tool& tool, const Say& say) {
  const int gouges = plan.gouging_contacts();
  if (gouges == 0) return "";
  Eigen::Vector3d at = Eigen::Vector3d::Zero();
  for (const auto& z : plan.zones) {
    const auto p = std::find_if(z.passes.begin(), z.passes.end(), [](const PlanePass& q) { return q.gouging_contacts > 0; });
    if (p != z.passes.end()) {
      at = p->first_gouge;
      break;
    }
  }
  std::ostringstream msg;
  msg.precision(4);
  msg << "the " << tool.name() << " gouges the surface at " << gouges << " contact points, the first at (" << at.transpose()
      << ") mm: the ground across the passes is more concave than the tool's trace there";
  if (c.orientation) throw InputError(c.orientation_where + ": " + msg.str() + "; tilt the axis less, or use a ball or a smaller corner radius");
  const std::string note = msg.str() + " (a smaller tool, or a ball, avoids it)";
  say("  WARNING: " + note);
  return note;
}

// Stage 5, the yardstick: the shortest passes any parallel-plane path keeping eq. 2.3 at every point
// can have on this face (length_bound.hpp), against the path's. With the axis the case fixes, or Z
// for 3-axis zoning; a 3+2 search may turn each zone, so its floor takes every point at the tool's
// level-ground step, the widest any axis allows.
json length_floor(const FinishCase& c, const FinishingSettings& settings, const FinishingPlan& plan, const Say& say) {
  const bool any_axis = !c.orientation && c.optimize && c.setup != SetupMode::three_axis;
  const Eigen::Vector3d axis = c.orientation ? tilted_setup((*c.orientation)(0), (*c.orientation)(1), 0, Eigen::Vector3d::Zero()).axis() : Eigen::Vector3d::UnitZ();
  CuttingLengthBound floor = shortest_cutting_length(c.surface.surface, c.surface.trim, settings.tool, settings.scallop, settings.timer.cutting(), 200, axis);
  if (any_axis) {
    floor.length = floor.area / level_ground_stepover(settings.tool, settings.scallop);
    floor.time = floor.length / settings.timer.cutting().feed;
  }
  std::ostringstream line;
  line.precision(4);
  line << "  passes " << plan.pass_length() << " mm against a floor of " << floor.length << " mm (" << (any_axis ? "any axis" : "this axis") << ", eq. 2.3 at every point)";
  say(line.str());
  return {{"length_mm", floor.length},
          {"time_at_feed_s", floor.time},
          {"area_mm2", floor.area},
          {"axis", any_axis ? "any (3+2: the level-ground step everywhere)" : c.orientation ? "the case's fixed axis" : "Z"},
          {"passes_over_floor", plan.pass_length() / floor.length}};
}

// Stage 6's program: machine/'s inverse kinematics, feed predictor and post-processor on the case's
// machine, then the posted text read back and judged (machine/program_verdict.hpp). A program the
// machine cannot run is not written: the run ends with exit 3 and `refused` says why.
struct PostedProgram {
  double predicted_cycle_time = -1;  // s, of the CL path as planned; < 0: no program
  std::optional<machine::ProgramVerdict> verdict;
  std::string refused;
};

PostedProgram post_program(const FinishCase& c, const machine::Machine& m, const FinishingPlan& plan, const FinishingSettings& settings,
                           const std::filesystem::path& out, std::vector<std::string>& files, const Say& say) {
  PostedProgram posted;
  try {
    const machine::Kinematics kinematics(m);
    const machine::ClProgram cl = cl_program(plan, settings.tool, settings.timer.cutting().feed * 60, settings.clearance, settings.approach);
    const machine::ClOnMachine on = machine::cl_to_machine_program(cl, kinematics);
    if (!on.joints.violations.empty()) {
      posted.refused = "on " + m.name + ", " + on.joints.violations.front().what;
    } else {
      posted.predicted_cycle_time = machine::predict_feed(on.program, kinematics).cycle_time;
      machine::PostOptions post = c.program;
      post.title = "drom finish " + c.name;
      post.tool_diameter = 2 * settings.tool.radius;
      const std::string text = machine::post_process(cl, kinematics, post);
      posted.verdict = machine::judge_program(text, "program.ngc", kinematics);
      if (!posted.verdict->runnable()) {
        posted.refused = "on " + m.name + ", " + posted.verdict->beyond_strokes.front().what;
      } else {
        write_file_atomically(out / "program.ngc", text);
        files.push_back("program.ngc");
        say("  program.ngc on " + m.name + ": " + posted.verdict->summary_line());
        if (posted.verdict->slows_down()) say("  warning: at its programmed feed the program asks more than the machine's axes give: the machine slows down (the cycle time above is what it reaches)");
      }
    }
  } catch (const InputError& e) {
    posted.refused = e.what();
  }
  if (!posted.refused.empty()) say("  no runnable program: " + posted.refused);
  return posted;
}

// Stage 6's history: each K's best time against the search's spending (CSV and PNG).
void write_optimization_history(const FinishCase& c, const std::vector<KOptimum>& optima, const std::filesystem::path& out, std::vector<std::string>& files) {
  if (optima.empty()) return;
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
  write_file_atomically(out / "history.csv", csv.str());
  files.push_back("history.csv");
  if (write_png_plot(out / "history.png", plot)) files.push_back("history.png");
}

// Everything the summary reports, by name.
struct FinishResults {
  const Described& described;
  const Zoning& zoning;
  const FinishingPlan& plan;
  const std::string& gouge_note;
  const ScallopCheck& check;
  const PostedProgram& program;
  const json& floor;
  const std::vector<std::string>& files;
};

json finish_summary(const FinishCase& c, const FinishResults& r) {
  const FinishingSettings& settings = r.described.settings;
  const PcaPlane& plane = r.described.plane;
  const ToolVerdict& verdict = r.described.verdict;
  const FinishingPlan& plan = r.plan;
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
  if (r.program.predicted_cycle_time >= 0) s["predicted_cycle_time_s"] = r.program.predicted_cycle_time;
  s["pca"] = {{"lambda", {plane.lambda(0), plane.lambda(1), plane.lambda(2)}},
              {"shape_factor", plane.shape_factor},
              {"size_mm2", plane.size},
              {"slope_deg", plane.slope * kDeg},
              {"mean_local_slope_deg", mean_slope(r.described.normals) * kDeg},
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
  s["zones"] = r.zoning.zones.count();
  s["time_s"] = {{"total", plan.time()}, {"passes", plan.pass_time()}, {"links", plan.link_time()}, {"retracts", plan.retract_time()}, {"between_zones", plan.move_time}};
  s["length_mm"] = {{"total", plan.length()}, {"passes", plan.pass_length()}, {"links", plan.link_length()}};
  s["passes"] = plan.pass_count();
  s["length_floor"] = r.floor;
  double run_outs = 0;
  for (const auto& z : plan.zones)
    for (const auto& p : z.passes) run_outs += p.run_out_length;
  s["run_out"] = {{"longest_mm", settings.run_out}, {"contact_length_mm", run_outs}};
  s["gouging_contacts"] = plan.gouging_contacts();
  if (!r.gouge_note.empty()) s["gouge_warning"] = r.gouge_note;
  const ScallopCheck& check = r.check;
  s["scallop_check"] = {{"points", check.points}, {"max_height_mm", check.max_height}, {"max_gouge_mm", check.max_gouge}, {"worst_uv", {check.worst_uv.x(), check.worst_uv.y()}}, {"grid", "40 x 40 over the surface"}};
  for (const auto& k : r.zoning.optima)
    s["optimization"].push_back({{"clusters", k.clusters}, {"zones", k.zones.count()}, {"f0_s", k.start_time}, {"f_star_s", k.best_time}, {"gain", k.gain()},
                                 {"black_box_equivalents", k.spent}});
  if (r.program.verdict) s["program_verdict"] = r.program.verdict->to_json();
  if (!r.program.refused.empty()) s["program_refused"] = r.program.refused;
  s["files"] = r.files;
  return s;
}

}  // namespace

json run_finish(const FinishCase& c, const FinishRunOptions& options) {
  const auto started = std::chrono::steady_clock::now();
  const machine::Machine m = machine::load_machine(c.machine_definition);  // a wrong machine is found before the work
  RunFolder folder(options.out, {.resume = options.resume, .reused = {"optimization"}, .inputs = {c.origin}});
  FinishRunOptions o = options;
  o.out = folder.staging();
  const Say say = [&](const std::string& line) {
    if (!o.quiet) std::printf("%s\n", line.c_str());
    std::fflush(stdout);
  };
  const Described described = describe_surface(c, say);
  const Zoning zoning = zone_surface(c, o, described, say);
  const FinishingPlan plan = finish_zones(described, zoning, say);
  const std::string gouge_note = report_gouges(c, plan, described.settings.tool, say);
  const ScallopCheck check = check_scallop(c.surface.surface, plan.zones, described.settings.tool, 0, 1, 0, 1, 40, 40);
  const json floor = length_floor(c, described.settings, plan, say);

  std::vector<std::string> files = {"zones.vtu", "paths.vtp", "cl.csv", "breakdown.csv"};
  write_zone_map(o.out / "zones.vtu", c.surface.surface, described.problem.samples, zoning.zones);
  write_pass_polylines(o.out / "paths.vtp", plan, described.settings.tool);
  write_cl_csv(o.out / "cl.csv", plan, described.settings.tool);
  write_breakdown_csv(o.out / "breakdown.csv", plan);
  const PostedProgram program = post_program(c, m, plan, described.settings, o.out, files, say);
  write_optimization_history(c, zoning.optima, o.out, files);

  json s = finish_summary(c, {described, zoning, plan, gouge_note, check, program, floor, files});
  s["elapsed_s"] = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
  s["version"] = kVersion;
  write_summary(o.out, s);
  folder.commit();
  return s;
}

}  // namespace drom::paths
