// The offline job (offline/offline_job.hpp): the machining simulation, station by station.
#include "offline/offline_job.hpp"

#include "fem/elastic_problem.hpp"
#include "fem/node_sets.hpp"
#include "fem/target_surface.hpp"
#include "fem/vtk_output.hpp"
#include "offline/machining_run.hpp"
#include "offline/part_setup.hpp"
#include "offline/station_solvers.hpp"
#include "offline/activity_history.hpp"
#include "offline/job_team.hpp"
#include "offline/station_schedule.hpp"
#include "support/atomic_file.hpp"
#include "support/byte_stream.hpp"
#include "support/fnv_hash.hpp"
#include "support/file_format.hpp"
#include "support/hdf5_writer.hpp"
#include "support/input_error.hpp"
#include "support/kernel_threads.hpp"
#include "support/resources.hpp"
#include "support/summary.hpp"
#include "support/toml_reader.hpp"

#include <algorithm>
#include <array>
#include <atomic>
#include <chrono>
#include <cinttypes>
#include <cmath>
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

// Per-station results on disk (OUT/.checkpoint), so an interrupted run loses no finished station,
// the ranks of an MPI job share their work, and slices computed apart are merged:
//   manifest.txt             the job's identity (mode and case hash)
//   station_NNNNN.bin, final.bin   the job's key, the seconds its solve took, then one matrix (ByteWriter)
//   slices/slice_A_B.json    what each --stations A:B run was, where, and whether it finished
// The folder must be one every rank (and every slice) sees.
class Checkpoint {
 public:
  enum class Join {
    Fresh,     // a new job: refuses a folder holding an unfinished one (unless resuming)
    Resume,    // continue the job here, or start it
    Shared,    // join the job here or start it (a slice; the slices meet in one folder)
    Existing,  // the job must be here (drom merge; the ranks after rank 0)
  };
  Checkpoint(std::filesystem::path dir, const std::string& identity, Join join) : dir_(std::move(dir)), key_(fnv1a(identity)) {
    const auto manifest = dir_ / "manifest.txt";
    if (std::filesystem::exists(manifest)) {
      std::ifstream in(manifest);
      std::string found((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      if (found != identity)
        throw InputError(dir_.string() + ": holds an unfinished run of a different case or mode; it will not be mixed with this one "
                                         "(remove the folder or choose another --out)");
      if (join == Join::Fresh) throw InputError(dir_.string() + ": an unfinished run is here; pass --resume to continue it, or remove the folder");
    } else if (join == Join::Existing) {
      throw InputError(dir_.string() + ": no job's stations are here (run the slices with --stations a:b and the same --out first)");
    } else {
      // Station files without a manifest are not known to be this run's (a removal cut short): gone.
      std::filesystem::remove_all(dir_);
      std::filesystem::create_directories(dir_);
      write_file_atomically(manifest, identity);
    }
  }
  std::filesystem::path file(const std::string& name) const { return dir_ / (name + ".bin"); }
  bool has(const std::string& name) const { return std::filesystem::exists(file(name)); }
  void save(const std::string& name, const Eigen::MatrixXd& m, double seconds) const {
    ByteWriter w;
    w.put(key_);
    w.put(seconds);
    w.put(m);
    write_file_atomically(file(name), w.bytes());
  }
  // The seconds a saved file's solve took (its header only: the schedule reads it for every station);
  // 0 when the file is missing or not this job's.
  double seconds(const std::string& name) const {
    std::ifstream in(file(name), std::ios::binary);
    std::array<char, sizeof key_ + sizeof(double)> header{};
    if (!in.read(header.data(), header.size())) return 0;
    ByteReader r(std::string_view(header.data(), header.size()), file(name).string());
    if (r.get<std::uint64_t>() != key_) return 0;
    const double s = r.get<double>();
    return std::isfinite(s) && s > 0 ? s : 0;
  }
  // Throws InputError naming the file (and the slice that should have written it) when it is not
  // this job's.
  Eigen::MatrixXd load(const std::string& name, std::size_t station) const {
    std::ifstream in(file(name), std::ios::binary);
    const std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    ByteReader r(bytes, file(name).string());
    if (bytes.size() < sizeof key_ || r.get<std::uint64_t>() != key_)
      throw InputError(file(name).string() + ": written by another job" + slice_holding(station) + ", not this one's; remove it and rerun its stations");
    r.get<double>();  // the seconds its solve took: the schedule's, not the database's
    Eigen::MatrixXd m = r.matrix();
    if (!r.done()) throw InputError(file(name).string() + ": malformed checkpoint" + slice_holding(station));
    return m;
  }
  // A slice's record, rewritten as it progresses.
  void record_slice(const StationRange& range, const nlohmann::json& record) const {
    std::filesystem::create_directories(dir_ / "slices");
    write_file_atomically(dir_ / "slices" / ("slice_" + std::to_string(range.first) + "_" + std::to_string(range.last) + ".json"), record.dump(1) + "\n");
  }
  // " (slice 40:80 on node3, unfinished)" for the slice whose record covers station k; "" if none.
  std::string slice_holding(std::size_t k) const {
    std::error_code error;
    for (const auto& entry : std::filesystem::directory_iterator(dir_ / "slices", error)) {
      std::ifstream in(entry.path());
      const auto record = nlohmann::json::parse(in, nullptr, false);
      if (record.is_discarded() || !record.contains("first") || !record.contains("last")) continue;
      if (k >= record["first"].get<std::size_t>() && k < record["last"].get<std::size_t>())
        return " (slice " + record.value("stations", std::string("?")) + " on " + record.value("host", std::string("?")) + ", " +
               (record.value("finished", false) ? "finished" : "unfinished") + ")";
    }
    return "";
  }
  // The manifest first: a removal cut short leaves no manifest over a partial set of stations.
  void remove() const {
    std::filesystem::remove(dir_ / "manifest.txt");
    std::filesystem::remove_all(dir_);
  }

 private:
  std::filesystem::path dir_;
  std::uint64_t key_;
};

std::string host_name() {
  char name[256] = {};
  return gethostname(name, sizeof name - 1) == 0 ? std::string(name) : std::string("?");
}

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
  const paths::ToolAssembly tool = build_tool(c);
  h5.attribute("tool_kind", c.tool_kind);
  h5.attribute("tool_radius", tool.cutter.radius);
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
    const Eigen::MatrixXd W = o.checkpoint->load(station_name(k), k);
    if (W.rows() != static_cast<Eigen::Index>(nt + ntop) || W.cols() != P) throw InputError(o.checkpoint->file(station_name(k)).string() + ": not this run's station");
    for (std::size_t i = 0; i < nt; ++i)
      for (Eigen::Index p = 0; p < P; ++p) B1[(k * nt + i) * static_cast<std::size_t>(P) + static_cast<std::size_t>(p)] = W(static_cast<Eigen::Index>(i), p);
    for (std::size_t i = 0; i < ntop; ++i)
      for (Eigen::Index p = 0; p < P; ++p) B1_top[(k * ntop + i) * static_cast<std::size_t>(P) + static_cast<std::size_t>(p)] = W(static_cast<Eigen::Index>(nt + i), p);
  }
  const Eigen::MatrixXd U2 = o.checkpoint->load("final", ns);
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
// each output's database is what a pass of its own would write, bit for bit. With several ranks
// (offline/job_team.hpp), rank 0 sweeps the removal and equilibrates the stock, every rank solves
// its block of stations, and rank 0 writes the databases: the same bytes, whatever the ranks.
std::vector<JobResult> simulate(std::vector<Output>& outputs) {
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return seconds_since(start); };
  const bool interactive = isatty(2) != 0;
  const JobOptions& options = outputs.front().options;  // quiet, threads, stop_after, progress, stations, merge, team
  SoloTeam solo;
  JobTeam& team = options.team ? *options.team : solo;
  const bool quiet = options.quiet || !team.root();
  // The part from the case that names the truth: the cases may differ by [truth] only (and by the
  // loop's tables, which no machining reads), or the pass would not be theirs.
  const auto with_truth = std::find_if(outputs.begin(), outputs.end(), [](const Output& o) { return o.truth; });
  const cases::Case& c = (with_truth != outputs.end() ? *with_truth : outputs.front()).c;
  std::unique_ptr<PartModel> part_model;
  std::vector<int> clamped, target, top;
  std::vector<fem::StressProfile> profiles;
  std::vector<int> groups;
  on_every_rank(team, [&] {
    const std::vector<std::string> not_machining = {"truth", "sensor", "sync", "control", "run"};
    for (const auto& o : outputs)
      if (case_text_without(o.c.resolved_toml, not_machining, {}, "") != case_text_without(c.resolved_toml, not_machining, {}, ""))
        throw std::invalid_argument("one machining pass for " + o.c.origin + " and " + c.origin + ": their cases machine different parts");
    part_model = std::make_unique<PartModel>(build_part(c));
    const auto& mesh = part_model->mesh;
    clamped = clamp_dofs(c, *part_model);
    try {
      target = fem::target_surface_nodes(mesh, part_model->shape, {c.pocket_x, c.pocket_x + c.pocket_length_x, c.pocket_y, c.pocket_y + c.pocket_length_y,
                                                                   part_model->shape.thickness() - c.pocket_depth});
    } catch (const std::invalid_argument& e) {
      throw InputError(c.origin + ": mesh.nz: " + e.what());
    }
    // The stock's top face, all of it: where the tool has not been, a laser reads it, and its w is an
    // absolute measurement (not a difference since a cut, as on the floor).
    top = fem::target_surface_nodes(mesh, part_model->shape, {0, part_model->shape.length_u(), 0, part_model->shape.length_v(), part_model->shape.thickness()});
    for (auto& o : outputs) {
      o.profiles = o.truth ? std::vector<fem::StressProfile>{part_model->truth_profile} : fem::unit_profiles(part_model->degrees);
      o.first = static_cast<Eigen::Index>(profiles.size());
      profiles.insert(profiles.end(), o.profiles.begin(), o.profiles.end());
      groups.push_back(static_cast<int>(o.profiles.size()));
      o.mode = o.truth ? "truth" : "offline";
      o.case_hash = fnv1a(o.c.resolved_toml);
    }
  });
  const PartModel& part = *part_model;
  const auto& mesh = part.mesh;
  // The shared checkpoint folder: rank 0 opens (or starts) it, the other ranks join it after. Rows per
  // station: the target's nodes, then the top's ("+top+key": checkpoints of older runs are not mixed in).
  auto open_checkpoints = [&](Checkpoint::Join join) {
    for (auto& o : outputs) o.checkpoint = std::make_unique<Checkpoint>(o.options.out / ".checkpoint", o.mode + "+top+key " + hex(o.case_hash) + "\n", join);
  };
  const Checkpoint::Join join = options.merge ? Checkpoint::Join::Existing
                                : !options.stations.empty() ? Checkpoint::Join::Shared
                                : options.resume ? Checkpoint::Join::Resume
                                                 : Checkpoint::Join::Fresh;
  on_root_then_broadcast(team, [&] {
    open_checkpoints(join);
    return std::string();
  });
  on_every_rank(team, [&] {
    if (!team.root()) open_checkpoints(Checkpoint::Join::Existing);
  });
  std::string modes;
  for (const auto& o : outputs) modes += (modes.empty() ? "" : " + ") + o.mode;

  // 1. Removal, on rank 0: the activity of every station (level set, a few seconds), as what changes
  //    from one station to the next; every rank replays it.
  std::unique_ptr<MachiningRun> run;
  const ActivityHistory history = ActivityHistory::from_bytes(on_root_then_broadcast(team, [&] {
    run = std::make_unique<MachiningRun>(c, part);
    ActivityHistory swept(static_cast<std::size_t>(mesh.element_count()));
    std::vector<double> remaining(static_cast<std::size_t>(mesh.element_count()), 1.0);
    for (std::size_t k = 0; k < run->stations().size(); ++k) {
      run->advance(remaining);
      swept.append(remaining);
    }
    return swept.bytes();
  }), "rank 0's removal");
  const std::size_t ns = history.stations();
  const double removal_seconds = elapsed();
  const auto P = static_cast<Eigen::Index>(profiles.size());
  if (!quiet)
    std::cerr << "drom " << modes << ": " << c.name << ": " << ns << " stations, " << mesh.dof_count() << " unknowns, " << P << " profile"
              << (P > 1 ? "s" : "") << ", " << target.size() << " target-surface nodes (removal " << removal_seconds << " s)"
              << (team.size() > 1 ? ", " + std::to_string(team.size()) + " ranks" : "") << "\n";
  StationRange range{0, ns};
  on_every_rank(team, [&] {
    if (!options.stations.empty()) range = parse_station_range(options.stations, ns, "--stations");
  });

  // Station workers fill the cores; threads inside each factorization would fight them (measured: a
  // third of the run in system time). Single-threaded kernels also round the same way whatever
  // --threads is, so the database does not depend on it.
  const SingleThreadedKernels single_threaded_kernels;

  // 2. Equilibrate once, on rank 0; every rank adopts it, and every worker from its rank.
  std::unique_ptr<StationSolvers> solvers;
  const std::string equilibrium = on_root_then_broadcast(team, [&] {
    solvers = StationSolvers::create(c, part, profiles, clamped, groups);
    return solvers->equilibrium();
  });
  nlohmann::json chunk_plan;
  on_every_rank(team, [&] {
    if (!team.root()) solvers = StationSolvers::create(c, part, profiles, clamped, groups, equilibrium);
    // Every rank from the same history and pattern: the same chunks everywhere.
    chunk_plan = solvers->plan(history);
  });
  const double equilibrium_seconds = elapsed() - removal_seconds;

  auto saved_by_all = [&](const std::string& name) {
    return std::all_of(outputs.begin(), outputs.end(), [&](const Output& o) { return o.checkpoint->has(name); });
  };
  // 3. The stations still missing, dealt out by rank 0 in contiguous blocks of chunks (a warm-starting
  //    solver's chunk is solved in order from its first station), balanced by their estimated cost:
  //    the cost law calibrated on the solve times the stations already saved measured.
  std::size_t done_before = 0;
  std::size_t measured_stations = 0;
  std::vector<std::size_t> missing;  // rank 0's view, for merge's refusal
  const std::string dealt = on_root_then_broadcast(team, [&] {
    std::vector<double> measured(ns, 0.0);
    for (std::size_t k = 0; k < ns; ++k) {
      if (saved_by_all(station_name(k))) {
        ++done_before;
        measured[k] = outputs.front().checkpoint->seconds(station_name(k));
        measured_stations += measured[k] > 0;
      } else {
        missing.push_back(k);
      }
    }
    if (options.merge && !missing.empty()) {
      std::string list;
      for (std::size_t i = 0; i < missing.size();) {
        std::size_t j = i;
        while (j + 1 < missing.size() && missing[j + 1] == missing[j] + 1) ++j;
        if (list.size() > 400) {
          list += ", ...";
          break;
        }
        list += (list.empty() ? "" : ", ") + to_string(StationRange{missing[i], missing[j] + 1}) + outputs.front().checkpoint->slice_holding(missing[i]);
        i = j + 1;
      }
      throw InputError((outputs.front().options.out / ".checkpoint").string() + ": " + std::to_string(missing.size()) + " of " + std::to_string(ns) +
                       " stations are missing, stations " + list + " (a:b is stations a to b - 1); run them with --stations a:b, then merge again");
    }
    const auto tasks = chunk_tasks(ns, solvers->chunk(), [&](std::size_t k) { return range.contains(k) && !saved_by_all(station_name(k)); },
                                   calibrated_costs(station_costs(history), measured));
    const auto blocks = deal_blocks(tasks, team.size(), 0);
    ByteWriter w;
    w.put<std::uint64_t>(done_before);
    for (const auto& block : blocks) {
      w.put<std::uint64_t>(block.size());
      for (const auto& t : block) w.put<std::uint64_t>(t.first), w.put<std::uint64_t>(t.last), w.put(t.cost);
    }
    return w.take();
  });
  std::vector<ChunkTask> mine;
  {
    ByteReader r(dealt, "rank 0's schedule");
    done_before = r.get<std::uint64_t>();
    for (int rank = 0; rank < team.size(); ++rank) {
      const auto count = r.get<std::uint64_t>();
      for (std::uint64_t i = 0; i < count; ++i) {
        ChunkTask t;
        t.first = r.get<std::uint64_t>();
        t.last = r.get<std::uint64_t>();
        t.cost = r.get<double>();
        if (rank == team.rank()) mine.push_back(t);
      }
    }
  }
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
  auto slice_record = [&](bool finished, std::size_t saved) {
    if (options.stations.empty()) return;
    const nlohmann::json record{{"stations", to_string(range)}, {"first", range.first}, {"last", range.last},
                                {"host", host_name()}, {"ranks", team.size()},
                                {"finished", finished}, {"stations_saved_by_this_run", saved}};
    for (const auto& o : outputs) o.checkpoint->record_slice(range, record);
  };
  on_root_then_broadcast(team, [&] {
    slice_record(false, 0);
    return std::string();
  });
  std::mutex report;
  auto print_progress = [&](std::size_t done) {
    const bool report_now = interactive || done % std::max<std::size_t>(1, ns / 50) == 0 || done == ns;
    if (quiet || !report_now) return;
    const double rate = static_cast<double>(done - done_before) / std::max(1e-9, elapsed() - removal_seconds - equilibrium_seconds);
    std::fprintf(stderr, "%s  station %zu/%zu  %.2f stations/s  %.0f s left%s", interactive ? "\r" : "", done, ns, rate,
                 static_cast<double>(ns - done) / std::max(1e-9, rate), interactive ? "   " : "\n");
  };
  std::atomic<std::size_t> next{0};
  std::atomic<int> solved{0};
  StationWork work;
  nlohmann::json solver_statistics = nlohmann::json::object();
  auto worker = [&] {
    try {
      // Again here: OpenMP's max-active-levels is kept per thread, so a worker thread starts with
      // CHOLMOD's teams of four (measured: 22 % of a PGD run's CPU time went to the system, 36 000
      // futex calls a second).
      const SingleThreadedKernels worker_kernels;
      const auto solver = solvers->make_worker();
      bool stopped = false;
      std::vector<double> activity;
      for (std::size_t j = next++; j < mine.size() && !stopped && !work.cancelled(); j = next++) {
        const ChunkTask task = mine[j];
        // A chunk restarts from its first station (cold), so a resumed run solves exactly what an
        // uninterrupted one does; finished stations are recomputed but not written again.
        activity = history.at(task.first);
        // The whole chunk's changes, also where a slice or a resume solves only part of it: the same
        // block, so the same round-off.
        if (solvers->chunk() > 1) solver->start_chunk(history.run_changes(task.first, std::min(ns, task.first + solvers->chunk()), fem::ElasticProblem::kMinVolumeFraction));
        for (std::size_t k = task.first; k < task.last; ++k) {
          if (k > task.first) history.advance(k, activity);
          const bool saved = !range.contains(k) || saved_by_all(station_name(k));
          if (!saved && (work.cancelled() || (options.stop_after >= 0 && solved.fetch_add(1) >= options.stop_after))) {
            stopped = true;
            break;
          }
          const auto solve_start = std::chrono::steady_clock::now();
          const Eigen::MatrixXd U = solver->solve(activity, k > task.first);
          const double solve_seconds = seconds_since(solve_start);
          if (saved) continue;
          for (const auto& o : outputs) {
            if (o.checkpoint->has(station_name(k))) continue;
            Eigen::MatrixXd W(static_cast<Eigen::Index>(target.size() + top.size()), o.count());
            for (std::size_t i = 0; i < target.size(); ++i) W.row(static_cast<Eigen::Index>(i)) = U.row(3 * target[i] + 2).segment(o.first, o.count());
            for (std::size_t i = 0; i < top.size(); ++i)
              W.row(static_cast<Eigen::Index>(target.size() + i)) = U.row(3 * top[i] + 2).segment(o.first, o.count());
            if (frame_at(k, ns, o.frames)) solver->write_vtu(o.options.out / "frames" / (station_name(k) + ".vtu"), names(o, U), static_cast<std::size_t>(o.first));
            o.checkpoint->save(station_name(k), W, solve_seconds);
          }
          const std::size_t saved_here = work.saved_one();
          if (team.reports_per_station()) {
            std::lock_guard<std::mutex> lock(report);
            print_progress(done_before + saved_here);
            if (options.progress && !options.progress(done_before + saved_here, ns)) work.cancel();
          }
        }
      }
      std::lock_guard<std::mutex> lock(report);
      accumulate(solver_statistics, solver->statistics());
    } catch (...) {
      work.fail(std::current_exception());
    }
    work.worker_done();
  };
  std::vector<std::thread> pool;
  work.start(threads);
  for (int t = 0; t < threads; ++t) pool.emplace_back(worker);
  try {
    // Rank 0 reports the whole job's progress (several ranks: a few times a second).
    team.supervise(work, [&](std::size_t saved) {
      print_progress(done_before + saved);
      return !options.progress || options.progress(done_before + saved, ns);
    });
  } catch (...) {
    work.cancel();
    for (auto& t : pool) t.join();
    throw;
  }
  for (auto& t : pool) t.join();
  if (!quiet && interactive) std::cerr << "\n";
  // Every rank's solver figures, summed on rank 0.
  const auto figures = team.gather(solver_statistics.dump());
  for (std::size_t r = 1; r < figures.size(); ++r) accumulate(solver_statistics, nlohmann::json::parse(figures[r]));

  // 4. and 5., on rank 0: the free final shape (best-fit alignment, one column per profile) and each
  //    database, from the checkpoints (so a resumed or distributed run writes the same bytes).
  std::vector<JobResult> results(outputs.size());
  const std::string summaries = on_root_then_broadcast(team, [&] {
    std::size_t finished = 0;
    for (std::size_t k = 0; k < ns; ++k) finished += saved_by_all(station_name(k));
    nlohmann::json all = nlohmann::json::array();
    if (!options.stations.empty()) {
      std::size_t in_range = 0;
      for (std::size_t k = range.first; k < range.last; ++k) in_range += saved_by_all(station_name(k));
      slice_record(in_range == range.size(), work.saved());
      if (!quiet)
        std::cerr << "drom " << modes << ": slice " << to_string(range) << ": " << in_range << " of " << range.size() << " stations saved; " << finished
                  << " of " << ns << " in the job" << (finished == ns ? ": drom merge writes the database\n" : "\n");
      return nlohmann::json{{"saved", finished}, {"summaries", all}}.dump();
    }
    if (finished < ns) {
      if (!quiet) std::cerr << "drom " << modes << ": stopped after " << finished << " of " << ns << " stations; continue with --resume\n";
      return nlohmann::json{{"saved", finished}, {"summaries", all}}.dump();
    }
    const std::vector<double> final_activity = history.at(ns - 1);
    if (!saved_by_all("final")) {
      const auto solver = solvers->make_worker();
      const auto solve_start = std::chrono::steady_clock::now();
      const Eigen::MatrixXd U = solver->free_shape(final_activity);
      const double solve_seconds = seconds_since(solve_start);
      accumulate(solver_statistics, {{"final_shape", solver->statistics()}});
      for (const auto& o : outputs) {
        if (o.checkpoint->has("final")) continue;
        solver->write_vtu(o.options.out / "final_free_shape.vtu", names(o, U), static_cast<std::size_t>(o.first));
        o.checkpoint->save("final", U.middleCols(o.first, o.count()), solve_seconds);
      }
    }
    for (auto& o : outputs)
      all.push_back(write_database(o, part, target, top, run->stations(), run->path(), final_activity, elapsed, removal_seconds,
                                   {{"threads", threads},
                                    {"ranks", team.size()},
                                    {"solver", c.solver},
                                    {"solver_statistics", solver_statistics},
                                    {"equilibrium", solvers->equilibrium_statistics()},
                                    {"chunk_plan", chunk_plan},
                                    {"equilibrium_time_s", equilibrium_seconds},
                                    {"deal_measured_stations", measured_stations},
                                    {"pass_outputs", modes}}));
    return nlohmann::json{{"saved", finished}, {"summaries", all}}.dump();
  });
  const auto outcome = nlohmann::json::parse(summaries);
  for (std::size_t i = 0; i < results.size(); ++i) {
    results[i].stations = ns;
    results[i].stations_saved = outcome["saved"].get<std::size_t>();
    results[i].finished = i < outcome["summaries"].size();
    if (results[i].finished) results[i].summary = outcome["summaries"][i];
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
