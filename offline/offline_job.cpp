// The offline job (offline/offline_job.hpp): the machining simulation, station by station.
#include "offline/offline_job.hpp"

#include "fem/elastic_problem.hpp"
#include "fem/node_sets.hpp"
#include "fem/target_surface.hpp"
#include "fem/vtk_output.hpp"
#include "offline/machining_run.hpp"
#include "offline/part_setup.hpp"
#include "offline/station_solvers.hpp"
#include "support/atomic_file.hpp"
#include "support/file_format.hpp"
#include "support/hdf5_writer.hpp"
#include "support/input_error.hpp"
#include "support/kernel_threads.hpp"
#include "support/resources.hpp"
#include "support/summary.hpp"
#include "support/toml_reader.hpp"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cinttypes>
#include <cstdio>
#include <exception>
#include <fstream>
#include <iostream>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>
#include <thread>
#include <unistd.h>

namespace drom::offline {

namespace {

std::uint64_t fnv1a(const void* data, std::size_t bytes, std::uint64_t hash = 1469598103934665603ull) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < bytes; ++i) hash = (hash ^ p[i]) * 1099511628211ull;
  return hash;
}

std::string hex(std::uint64_t v) {
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016" PRIx64, v);
  return buf;
}

// Per-station results on disk, so an interrupted run loses no finished station.
class Checkpoint {
 public:
  Checkpoint(std::filesystem::path dir, const std::string& identity, bool resume) : dir_(std::move(dir)) {
    const auto manifest = dir_ / "manifest.txt";
    if (std::filesystem::exists(manifest)) {
      std::ifstream in(manifest);
      std::string found((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      if (found != identity)
        throw InputError(dir_.string() + ": holds an unfinished run of a different case or mode; it will not be mixed with this one "
                                         "(remove the folder or choose another --out)");
      if (!resume) throw InputError(dir_.string() + ": an unfinished run is here; pass --resume to continue it, or remove the folder");
    } else {
      // Station files without a manifest are not known to be this run's (a removal cut short): gone.
      std::filesystem::remove_all(dir_);
      std::filesystem::create_directories(dir_);
      write_file_atomically(manifest, identity);
    }
  }
  std::filesystem::path file(const std::string& name) const { return dir_ / (name + ".bin"); }
  bool has(const std::string& name) const { return std::filesystem::exists(file(name)); }
  void save(const std::string& name, const Eigen::MatrixXd& m) const {
    std::string bytes(sizeof(Eigen::Index) * 2 + sizeof(double) * static_cast<std::size_t>(m.size()), '\0');
    const Eigen::Index dims[2] = {m.rows(), m.cols()};
    std::memcpy(bytes.data(), dims, sizeof dims);
    std::memcpy(bytes.data() + sizeof dims, m.data(), sizeof(double) * static_cast<std::size_t>(m.size()));
    write_file_atomically(file(name), bytes);
  }
  Eigen::MatrixXd load(const std::string& name) const {
    std::ifstream in(file(name), std::ios::binary);
    Eigen::Index dims[2] = {0, 0};
    in.read(reinterpret_cast<char*>(dims), sizeof dims);
    // Its size must be what its dimensions say before anything is allocated from them.
    std::error_code ec;
    const auto size = std::filesystem::file_size(file(name), ec);
    if (!in || ec || dims[0] < 0 || dims[1] < 0 || (dims[1] > 0 && dims[0] > static_cast<Eigen::Index>(size / 8) / dims[1]) ||
        size != sizeof dims + sizeof(double) * static_cast<std::size_t>(dims[0] * dims[1]))
      throw InputError(file(name).string() + ": a damaged checkpoint (" + std::to_string(ec ? 0 : size) + " bytes); remove " + dir_.string() + " to start over");
    Eigen::MatrixXd m(dims[0], dims[1]);
    in.read(reinterpret_cast<char*>(m.data()), static_cast<std::streamsize>(sizeof(double) * static_cast<std::size_t>(m.size())));
    if (!in) throw InputError(file(name).string() + ": truncated checkpoint");
    return m;
  }
  // The manifest first: a removal cut short leaves no manifest over a partial set of stations.
  void remove() const {
    std::filesystem::remove(dir_ / "manifest.txt");
    std::filesystem::remove_all(dir_);
  }

 private:
  std::filesystem::path dir_;
};

std::string station_name(std::size_t k) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "station_%05zu", k);
  return buf;
}

// Offline fields are named after their unit profile: `displacement_P2_11` = unit sigma11 coefficient
// of P2.
std::string profile_name(const fem::StressProfile& prof) {
  std::string name = "displacement";
  for (std::size_t j = 0; j < prof.degrees.size(); ++j) {
    if (prof.sigma11[j] != 0) name += "_P" + std::to_string(prof.degrees[j]) + "_11";
    if (prof.sigma22[j] != 0) name += "_P" + std::to_string(prof.degrees[j]) + "_22";
  }
  return name;
}

// One database the machining pass writes: the unit profiles' (drom offline) or the [truth] profile's
// (drom truth), each with its own case, --out, checkpoint and frames.
struct Output {
  JobOptions options;
  bool truth = false;
  cases::Case c;
  std::string mode;
  std::uint64_t case_hash = 0;
  std::vector<fem::StressProfile> profiles;
  Eigen::Index first = 0;  // its columns in the pass's solutions
  std::unique_ptr<Checkpoint> checkpoint;
  std::size_t frames = 0;
  Eigen::Index count() const { return static_cast<Eigen::Index>(profiles.size()); }
};

// Step 5 of simulate for one output: its database from its checkpoints (so a resumed run writes the
// same bytes), its frames' .pvd and its summary.json (`pass`: the figures of the pass, shared by its
// outputs).
// What drom reduce needs beside the snapshots, so that it reads the database alone: the target
// surface's and the final part's faces, the stock's top in the part's own coordinates, the pocket, the
// tool and the programmed path with its times.
void write_reduction_inputs(Hdf5Writer& h5, const cases::Case& c, const PartModel& part, const std::vector<int>& target, const std::vector<int>& top,
                            const levelset::Toolpath& path, const std::vector<double>& final_activity) {
  const auto& mesh = part.mesh;
  auto faces_dataset = [&](const std::string& name, const std::vector<fem::BoundaryFace>& faces, const std::map<int, int>& local) {
    std::vector<double> rows;
    for (const auto& f : faces)
      for (int n : f.nodes) rows.push_back(local.at(n));
    h5.write(name, rows, faces.size(), faces.empty() ? 1 : faces.front().nodes.size());
  };
  std::map<int, int> target_local;
  for (std::size_t i = 0; i < target.size(); ++i) target_local[target[i]] = static_cast<int>(i);
  const auto target_faces = fem::faces_within(mesh, target);
  if (target_faces.empty()) throw InputError(c.origin + ": no element face lies on the pocket's floor: refine mesh.nz so a layer boundary falls at its depth");
  faces_dataset("target_faces", target_faces, target_local);
  // The final part's surface: the boundary of the elements that keep material.
  fem::Mesh kept = mesh;
  kept.connectivity.clear();
  for (int e = 0; e < mesh.element_count(); ++e)
    if (final_activity[static_cast<std::size_t>(e)] > fem::ElasticProblem::kMinVolumeFraction)
      kept.connectivity.insert(kept.connectivity.end(), mesh.element(e).begin(), mesh.element(e).end());
  const auto shape_faces = fem::boundary_faces(kept);
  std::map<int, int> shape_local;
  for (const auto& f : shape_faces)
    for (int n : f.nodes) shape_local.emplace(n, 0);
  std::vector<double> shape_nodes;
  for (auto& [node, index] : shape_local) {
    index = static_cast<int>(shape_nodes.size());
    shape_nodes.push_back(node);
  }
  h5.write("shape_nodes", shape_nodes, shape_nodes.size(), 1);
  faces_dataset("shape_faces", shape_faces, shape_local);
  std::vector<double> top_uvt;
  for (int n : top) {
    const Eigen::Vector3d p = part.shape.to_parametric(mesh.nodes[static_cast<std::size_t>(n)]);
    top_uvt.insert(top_uvt.end(), {p.x(), p.y(), p.z()});
  }
  h5.write("top_parametric", top_uvt, top.size(), 3);
  std::map<int, int> top_local;
  for (std::size_t i = 0; i < top.size(); ++i) top_local[top[i]] = static_cast<int>(i);
  faces_dataset("top_faces", fem::faces_within(mesh, top), top_local);
  h5.write("pocket", std::vector<double>{c.pocket_x, c.pocket_y, c.pocket_length_x, c.pocket_length_y, c.pocket_depth}, 1, 5);
  const levelset::Tool tool = build_tool(c);
  h5.attribute("tool_kind", c.tool_kind);
  h5.attribute("tool_radius", tool.radius);
  const levelset::PathTimeline timeline(path);
  const auto waypoints = levelset::timed_waypoints(path, timeline);
  std::vector<double> xyzt(static_cast<std::size_t>(waypoints.xyzt.size())), cutting(waypoints.cutting.begin(), waypoints.cutting.end());
  for (Eigen::Index i = 0; i < waypoints.xyzt.rows(); ++i)
    for (Eigen::Index j = 0; j < 4; ++j) xyzt[static_cast<std::size_t>(4 * i + j)] = waypoints.xyzt(i, j);
  h5.write("path_waypoints", xyzt, static_cast<std::size_t>(waypoints.xyzt.rows()), 4);
  h5.write("path_cutting", cutting, cutting.size(), 1);
  // The case's own coefficients in the columns' order (sigma11's, then sigma22's), for the prior.
  std::vector<double> coefficients(c.sigma11);
  coefficients.insert(coefficients.end(), c.sigma22.begin(), c.sigma22.end());
  if (!coefficients.empty()) h5.write("case_coefficients", coefficients, 1, coefficients.size());
  h5.attribute("case_name", c.name);
}

template <class Elapsed>
nlohmann::json write_database(const Output& o, const PartModel& part, const std::vector<int>& target, const std::vector<int>& top,
                              const std::vector<levelset::Station>& stations, const levelset::Toolpath& path, const std::vector<double>& final_activity,
                              Elapsed&& elapsed, double removal_seconds, const nlohmann::json& pass) {
  const auto& mesh = part.mesh;
  const std::size_t ns = stations.size();
  const Eigen::Index P = o.count();
  const auto nt = target.size(), ntop = top.size();
  std::vector<double> B1(ns * nt * static_cast<std::size_t>(P)), B1_top(ns * ntop * static_cast<std::size_t>(P));
  for (std::size_t k = 0; k < ns; ++k) {
    const Eigen::MatrixXd W = o.checkpoint->load(station_name(k));
    if (W.rows() != static_cast<Eigen::Index>(nt + ntop) || W.cols() != P) throw InputError(o.checkpoint->file(station_name(k)).string() + ": not this run's station");
    for (std::size_t i = 0; i < nt; ++i)
      for (Eigen::Index p = 0; p < P; ++p) B1[(k * nt + i) * static_cast<std::size_t>(P) + static_cast<std::size_t>(p)] = W(static_cast<Eigen::Index>(i), p);
    for (std::size_t i = 0; i < ntop; ++i)
      for (Eigen::Index p = 0; p < P; ++p) B1_top[(k * ntop + i) * static_cast<std::size_t>(P) + static_cast<std::size_t>(p)] = W(static_cast<Eigen::Index>(nt + i), p);
  }
  const Eigen::MatrixXd U2 = o.checkpoint->load("final");
  std::vector<double> B2(static_cast<std::size_t>(U2.size()));
  for (Eigen::Index r = 0; r < U2.rows(); ++r)
    for (Eigen::Index p = 0; p < P; ++p) B2[static_cast<std::size_t>(r * P + p)] = U2(r, p);
  std::vector<double> target_xyz(3 * nt), target_ids(nt), nodes(3 * static_cast<std::size_t>(mesh.node_count()));
  for (std::size_t i = 0; i < nt; ++i) {
    target_ids[i] = target[i];
    for (int d = 0; d < 3; ++d) target_xyz[3 * i + static_cast<std::size_t>(d)] = mesh.nodes[static_cast<std::size_t>(target[i])][d];
  }
  std::vector<double> top_ids(top.begin(), top.end());
  for (int n = 0; n < mesh.node_count(); ++n)
    for (int d = 0; d < 3; ++d) nodes[3 * static_cast<std::size_t>(n) + static_cast<std::size_t>(d)] = mesh.nodes[static_cast<std::size_t>(n)][d];
  std::vector<double> connectivity(mesh.connectivity.begin(), mesh.connectivity.end());
  std::vector<double> unit(2 * static_cast<std::size_t>(P));
  for (Eigen::Index p = 0; p < P; ++p) {
    const auto& prof = o.profiles[static_cast<std::size_t>(p)];
    for (std::size_t j = 0; j < prof.degrees.size(); ++j) {
      if (prof.sigma11[j] != 0) unit[2 * static_cast<std::size_t>(p)] = 11, unit[2 * static_cast<std::size_t>(p) + 1] = prof.degrees[j];
      if (prof.sigma22[j] != 0) unit[2 * static_cast<std::size_t>(p)] = 22, unit[2 * static_cast<std::size_t>(p) + 1] = prof.degrees[j];
    }
  }
  std::uint64_t content = fnv1a(B1.data(), B1.size() * sizeof(double), o.case_hash);
  content = fnv1a(B2.data(), B2.size() * sizeof(double), content);
  content = fnv1a(B1_top.data(), B1_top.size() * sizeof(double), content);
  {
    Hdf5Writer h5(o.options.out / "database.h5");
    write_file_format(h5, kSnapshotDatabase);
    h5.write("B1", B1, ns * nt, static_cast<std::size_t>(P));
    h5.write("B2", B2, static_cast<std::size_t>(U2.rows()), static_cast<std::size_t>(P));
    h5.write("B1_top", B1_top, ns * ntop, static_cast<std::size_t>(P));
    h5.write("top_nodes", top_ids, ntop, 1);
    write_stations(h5, stations);
    h5.write("target_nodes", target_ids, nt, 1);
    h5.write("target_coordinates", target_xyz, nt, 3);
    h5.write("node_coordinates", nodes, static_cast<std::size_t>(mesh.node_count()), 3);
    h5.write("connectivity", connectivity, static_cast<std::size_t>(mesh.element_count()), static_cast<std::size_t>(fem::nodes_per_element(mesh.type)));
    h5.write("final_activity", final_activity, final_activity.size(), 1);
    if (o.truth) {
      const auto& truth_profile = part.truth_profile;
      std::vector<double> coefficients(truth_profile.sigma11);
      coefficients.insert(coefficients.end(), truth_profile.sigma22.begin(), truth_profile.sigma22.end());
      h5.write("profile_coefficients", coefficients, 2, truth_profile.degrees.size());
    } else {
      h5.write("unit_profiles", unit, static_cast<std::size_t>(P), 2);
    }
    const auto& written_degrees = o.truth ? part.truth_profile.degrees : part.degrees;
    std::vector<double> degrees(written_degrees.begin(), written_degrees.end());
    h5.write("profile_degrees", degrees, degrees.size(), 1);
    h5.attribute("kind", o.mode);
    h5.attribute("case", o.c.resolved_toml);
    h5.attribute("case_hash", hex(o.case_hash));
    h5.attribute("content_hash", hex(content));
    h5.attribute("element", std::string(fem::element_name(mesh.type)));
    h5.attribute("layout", std::string("B1[(station * n_target + i), profile] = w of target node i at the station; "
                                       "B1_top[(station * n_top + i), profile] = w of the stock's top node i (top_nodes) at the station; "
                                       "B2[3 * node + component, profile] = free final shape after best-fit alignment"));
    write_reduction_inputs(h5, o.c, part, target, top, path, final_activity);
    h5.commit();
  }
  if (o.frames > 0) {
    fem::PvdCollection pvd;
    for (std::size_t k = 0; k < ns; ++k)
      if (frame_at(k, ns, o.frames)) pvd.add(stations[k].time, std::filesystem::path("frames") / (station_name(k) + ".vtu"));
    pvd.write(o.options.out / (o.mode + ".pvd"));
  }

  double max_w = 0;
  for (double v : B1) max_w = std::max(max_w, std::abs(v));
  const auto db_size = std::filesystem::file_size(o.options.out / "database.h5");
  nlohmann::json summary{{"command", o.mode},
                         {"case", o.c.name},
                         {"stations", ns},
                         {"unknowns", mesh.dof_count()},
                         {"profiles", P},
                         {"target_nodes", nt},
                         {"top_nodes", ntop},
                         {"time_s", elapsed()},
                         {"removal_time_s", removal_seconds},
                         {"time_per_station_s", (elapsed() - removal_seconds) / static_cast<double>(ns)},
                         {"peak_memory_mb", static_cast<double>(peak_memory_bytes()) / 1048576.0},
                         {"database_mb", static_cast<double>(db_size) / 1048576.0},
                         {"max_abs_B1_mm", max_w},
                         {"case_hash", hex(o.case_hash)},
                         {"content_hash", hex(content)},
                         {"machine", machine_info()},
                         {"frames", o.frames},
                         {"files", o.frames > 0 ? nlohmann::json{"database.h5", o.mode + ".pvd", "frames/", "final_free_shape.vtu"}
                                             : nlohmann::json{"database.h5", "final_free_shape.vtu"}}};
  summary.update(pass);
  write_summary(o.options.out, summary);
  o.checkpoint->remove();  // last: a job stopped before this resumes from its stations and writes all again
  return summary;
  if (!o.options.quiet)
    std::printf("drom %s: %s: %zu stations x %lld profile(s), %d unknowns, %.1f s (%.2f s per station on %d threads) -> %s/database.h5 (%.1f MB)\n",
                o.mode.c_str(), o.c.name.c_str(), ns, static_cast<long long>(P), mesh.dof_count(), elapsed(), (elapsed() - removal_seconds) / static_cast<double>(ns),
                pass.value("threads", 0), o.options.out.string().c_str(), static_cast<double>(db_size) / 1048576.0);
}

// The machining simulation, once for all `outputs` (one factorization per station serves them all);
// each output's database is what a pass of its own would write, bit for bit.
std::vector<JobResult> simulate(std::vector<Output>& outputs) {
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return seconds_since(start); };
  const bool interactive = isatty(2) != 0;
  const JobOptions& options = outputs.front().options;  // quiet, threads, stop_after, progress
  // The part from the case that names the truth: the cases may differ by [truth] only (and by the
  // loop's tables, which no machining reads), or the pass would not be theirs.
  const auto with_truth = std::find_if(outputs.begin(), outputs.end(), [](const Output& o) { return o.truth; });
  const cases::Case& c = (with_truth != outputs.end() ? *with_truth : outputs.front()).c;
  const std::vector<std::string> not_machining = {"truth", "sensor", "sync", "control", "run"};
  for (const auto& o : outputs)
    if (case_text_without(o.c.resolved_toml, not_machining, {}, "") != case_text_without(c.resolved_toml, not_machining, {}, ""))
      throw std::invalid_argument("one machining pass for " + o.c.origin + " and " + c.origin + ": their cases machine different parts");
  const PartModel part = build_part(c);
  const auto& mesh = part.mesh;
  const auto clamped = clamp_dofs(c, part);
  std::vector<int> target;
  try {
    target = fem::target_surface_nodes(mesh, part.shape, {c.pocket_x, c.pocket_x + c.pocket_length_x, c.pocket_y, c.pocket_y + c.pocket_length_y,
                                                          part.shape.thickness() - c.pocket_depth});
  } catch (const std::invalid_argument& e) {
    throw InputError(c.origin + ": mesh.nz: " + e.what());
  }
  // The stock's top face, all of it: where the tool has not been, a laser reads it, and its w is an
  // absolute measurement (not a difference since a cut, as on the floor).
  const std::vector<int> top = fem::target_surface_nodes(mesh, part.shape, {0, part.shape.length_u(), 0, part.shape.length_v(), part.shape.thickness()});
  std::vector<fem::StressProfile> profiles;
  std::vector<int> groups;
  for (auto& o : outputs) {
    o.profiles = o.truth ? std::vector<fem::StressProfile>{part.truth_profile} : fem::unit_profiles(part.degrees);
    o.first = static_cast<Eigen::Index>(profiles.size());
    profiles.insert(profiles.end(), o.profiles.begin(), o.profiles.end());
    groups.push_back(static_cast<int>(o.profiles.size()));
    o.mode = o.truth ? "truth" : "offline";
    o.case_hash = fnv1a(o.c.resolved_toml.data(), o.c.resolved_toml.size());
    // Rows per station: the target's nodes, then the top's ("+top": checkpoints of runs before the
    // top was kept hold fewer rows and are not mixed in).
    o.checkpoint = std::make_unique<Checkpoint>(o.options.out / ".checkpoint", o.mode + "+top " + hex(o.case_hash) + "\n", o.options.resume);
  }
  std::string modes;
  for (const auto& o : outputs) modes += (modes.empty() ? "" : " + ") + o.mode;

  // 1. Removal: the activity of every station (level set, a few seconds).
  MachiningRun run(c, part);
  const auto& stations = run.stations();
  const std::size_t ns = stations.size();
  std::vector<std::vector<double>> activity(ns);
  std::vector<double> remaining(static_cast<std::size_t>(mesh.element_count()), 1.0);
  for (std::size_t k = 0; k < ns; ++k) {
    run.advance(remaining);
    activity[k] = remaining;
  }
  const double removal_seconds = elapsed();
  const auto P = static_cast<Eigen::Index>(profiles.size());
  if (!options.quiet)
    std::cerr << "drom " << modes << ": " << c.name << ": " << ns << " stations, " << mesh.dof_count() << " unknowns, " << P << " profile"
              << (P > 1 ? "s" : "") << ", " << target.size() << " target-surface nodes (removal " << removal_seconds << " s)\n";

  // Station workers fill the cores; threads inside each factorization would fight them (measured: a
  // third of the run in system time). Single-threaded kernels also round the same way whatever
  // --threads is, so the database does not depend on it.
  const SingleThreadedKernels single_threaded_kernels;

  // 2. Equilibrate once; every worker adopts it.
  const auto solvers = StationSolvers::create(c, part, profiles, clamped, groups);
  const double equilibrium_seconds = elapsed() - removal_seconds;

  // 3. Stations, in parallel (independent given activity, or chunks of them for a warm-starting
  //    solver), each one checkpointed.
  const int threads = options.threads > 0 ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  for (auto& o : outputs) {
    const int wanted = o.options.frames >= 0 ? o.options.frames : (o.truth ? 10 : 0);
    o.frames = static_cast<std::size_t>(std::min<int>(wanted, static_cast<int>(ns)));
  }
  auto names = [&](const Output& o, const Eigen::MatrixXd& U) {
    NamedDisplacements named;
    if (o.truth) named.emplace_back("displacement", U.col(o.first));
    for (Eigen::Index p = 0; !o.truth && p < o.count(); ++p) named.emplace_back(profile_name(o.profiles[static_cast<std::size_t>(p)]), U.col(o.first + p));
    return named;
  };
  auto saved_by_all = [&](const std::string& name) {
    return std::all_of(outputs.begin(), outputs.end(), [&](const Output& o) { return o.checkpoint->has(name); });
  };
  const std::size_t chunk = solvers->chunk();
  const std::size_t chunks = (ns + chunk - 1) / chunk;
  std::atomic<std::size_t> next{0};
  std::atomic<int> solved{0};
  std::atomic<bool> cancelled{false};  // the progress callback asked to stop
  std::mutex report;
  std::exception_ptr failure;
  nlohmann::json solver_statistics = nlohmann::json::object();
  std::size_t done_before = 0;
  for (std::size_t k = 0; k < ns; ++k) done_before += saved_by_all(station_name(k));
  auto worker = [&] {
    try {
      // Again here: OpenMP's max-active-levels is kept per thread, so a worker thread starts with
      // CHOLMOD's teams of four (measured: 22 % of a PGD run's CPU time went to the system, 36 000
      // futex calls a second).
      const SingleThreadedKernels worker_kernels;
      const auto solver = solvers->make_worker();
      bool stopped = false;
      for (std::size_t j = next++; j < chunks && !stopped && !cancelled; j = next++) {
        const std::size_t first = j * chunk, last = std::min(ns, first + chunk);
        std::size_t missing = first;
        while (missing < last && saved_by_all(station_name(missing))) ++missing;
        if (missing == last) continue;
        // A chunk restarts from its first station (cold), so a resumed run solves exactly what an
        // uninterrupted one does; finished stations are recomputed but not written again.
        for (std::size_t k = first; k < last; ++k) {
          const bool saved = saved_by_all(station_name(k));
          if (!saved && (cancelled || (options.stop_after >= 0 && solved.fetch_add(1) >= options.stop_after))) {
            stopped = true;
            break;
          }
          const Eigen::MatrixXd U = solver->solve(activity[k], k > first);
          if (saved) continue;
          for (const auto& o : outputs) {
            if (o.checkpoint->has(station_name(k))) continue;
            Eigen::MatrixXd W(static_cast<Eigen::Index>(target.size() + top.size()), o.count());
            for (std::size_t i = 0; i < target.size(); ++i) W.row(static_cast<Eigen::Index>(i)) = U.row(3 * target[i] + 2).segment(o.first, o.count());
            for (std::size_t i = 0; i < top.size(); ++i)
              W.row(static_cast<Eigen::Index>(target.size() + i)) = U.row(3 * top[i] + 2).segment(o.first, o.count());
            if (frame_at(k, ns, o.frames)) solver->write_vtu(o.options.out / "frames" / (station_name(k) + ".vtu"), names(o, U), static_cast<std::size_t>(o.first));
            o.checkpoint->save(station_name(k), W);
          }
          std::lock_guard<std::mutex> lock(report);
          const auto done = static_cast<double>(++done_before);
          const bool report_now = interactive || static_cast<std::size_t>(done) % std::max<std::size_t>(1, ns / 50) == 0 || static_cast<std::size_t>(done) == ns;
          if (!options.quiet && report_now) {
            const double rate = done / std::max(1e-9, elapsed() - removal_seconds - equilibrium_seconds);
            std::fprintf(stderr, "%s  station %zu/%zu  %.2f stations/s  %.0f s left%s", interactive ? "\r" : "", static_cast<std::size_t>(done), ns, rate,
                         (static_cast<double>(ns) - done) / rate, interactive ? "   " : "\n");
          }
          if (options.progress && !options.progress(static_cast<std::size_t>(done), ns)) cancelled = true;
        }
      }
      std::lock_guard<std::mutex> lock(report);
      accumulate(solver_statistics, solver->statistics());
    } catch (...) {
      std::lock_guard<std::mutex> lock(report);
      failure = std::current_exception();
    }
  };
  std::vector<std::thread> pool;
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
  for (auto& t : pool) t.join();
  if (!options.quiet && interactive) std::cerr << "\n";
  if (failure) std::rethrow_exception(failure);
  std::size_t finished = 0;
  for (std::size_t k = 0; k < ns; ++k) finished += saved_by_all(station_name(k));
  std::vector<JobResult> results(outputs.size());
  for (auto& r : results) {
    r.stations = ns;
    r.stations_saved = finished;
  }
  if (finished < ns) {
    if (!options.quiet) std::cerr << "drom " << modes << ": stopped after " << finished << " of " << ns << " stations; continue with --resume\n";
    return results;
  }

  // 4. The free final shape (best-fit alignment), one column per profile.
  if (!saved_by_all("final")) {
    const auto solver = solvers->make_worker();
    const Eigen::MatrixXd U = solver->free_shape(activity.back());
    accumulate(solver_statistics, {{"final_shape", solver->statistics()}});
    for (const auto& o : outputs) {
      if (o.checkpoint->has("final")) continue;
      solver->write_vtu(o.options.out / "final_free_shape.vtu", names(o, U), static_cast<std::size_t>(o.first));
      o.checkpoint->save("final", U.middleCols(o.first, o.count()));
    }
  }

  // 5. Each database, from its checkpoints (so a resumed run writes the same bytes).
  for (std::size_t i = 0; i < outputs.size(); ++i) {
    results[i].summary = write_database(outputs[i], part, target, top, stations, run.path(), activity.back(), elapsed, removal_seconds,
                                        {{"threads", threads},
                                         {"solver", c.solver},
                                         {"solver_statistics", solver_statistics},
                                         {"equilibrium", solvers->equilibrium_statistics()},
                                         {"equilibrium_time_s", equilibrium_seconds},
                                         {"pass_outputs", modes}});
    results[i].finished = true;
  }
  return results;
}

}  // namespace

JobResult run_job(const cases::Case& c, JobKind kind, const JobOptions& options) {
  std::vector<Output> outputs(1);
  outputs[0].options = options;
  outputs[0].truth = kind == JobKind::Truth;
  outputs[0].c = c;
  return simulate(outputs).front();
}

std::pair<JobResult, JobResult> run_offline_and_truth(const cases::Case& offline_case, const JobOptions& offline, const cases::Case& truth_case,
                                                      const JobOptions& truth) {
  std::vector<Output> outputs(2);
  outputs[0].options = offline;
  outputs[0].c = offline_case;
  outputs[1].options = truth;
  outputs[1].truth = true;
  outputs[1].c = truth_case;
  auto results = simulate(outputs);
  return {results[0], results[1]};
}

}  // namespace drom::offline
