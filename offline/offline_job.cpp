// The offline job (offline/offline_job.hpp): the machining simulation, station by station.
#include "offline/offline_job.hpp"
#include "support/run_folder.hpp"
#include "support/stop_request.hpp"

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
  case_file::Case c;
  std::string mode;
  std::uint64_t case_hash = 0;
  std::vector<fem::StressProfile> profiles;
  Eigen::Index first = 0;  // its columns in the pass's solutions
  std::unique_ptr<Checkpoint> checkpoint;
  std::size_t frames = 0;
  Eigen::Index count() const { return static_cast<Eigen::Index>(profiles.size()); }
};

// What drom reduce needs beside the snapshots, so that it reads the database alone: the target
// surface's and the final part's faces, the stock's top in the part's own coordinates, the pocket, the
// tool and the programmed path with its times.
void write_reduction_inputs(Hdf5Writer& h5, const case_file::Case& c, const PartModel& part, const std::vector<int>& target, const std::vector<int>& top,
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

// What the stages of one machining pass share.
struct Pass {
  std::vector<Output>& outputs;
  const JobOptions& options;  // the first output's: quiet, threads, stop_after, progress, stations, merge, team
  JobTeam& team;
  const case_file::Case& c;       // the case whose part is machined (machined_case)
  bool quiet = false;         // only rank 0 speaks
  bool interactive = false;   // stderr is a terminal: progress is one line rewritten in place
  std::chrono::steady_clock::time_point start = {};

  double elapsed() const { return seconds_since(start); }
  bool saved_by_all(const std::string& name) const {
    return std::all_of(outputs.begin(), outputs.end(), [&](const Output& o) { return o.checkpoint->has(name); });
  }
  // "offline", "truth" or "offline + truth": what messages and summary.json call the pass.
  std::string modes() const {
    std::string list;
    for (const auto& o : outputs) list += (list.empty() ? "" : " + ") + o.mode;
    return list;
  }
};

// The part from the case that names the truth: the cases may differ by [truth] only (and by the
// loop's tables, which no machining reads), or the pass would not be theirs.
const case_file::Case& machined_case(const std::vector<Output>& outputs) {
  const auto with_truth = std::find_if(outputs.begin(), outputs.end(), [](const Output& o) { return o.truth; });
  return (with_truth != outputs.end() ? *with_truth : outputs.front()).c;
}

// The part every rank builds, and every output's profiles side by side (the solvers' columns).
struct PassPart {
  std::unique_ptr<PartModel> model;
  std::vector<int> clamped, target, top;
  std::vector<fem::StressProfile> profiles;
  std::vector<int> groups;  // how many of the profiles each output has, in order
};

PassPart prepare_part(const Pass& pass) {
  const case_file::Case& c = pass.c;
  PassPart part;
  on_every_rank(pass.team, [&] {
    const std::vector<std::string> not_machining = {"truth", "sensor", "sync", "control", "run", "program"};
    for (const auto& o : pass.outputs)
      if (case_text_without(o.c.resolved_toml, not_machining, {}, "") != case_text_without(c.resolved_toml, not_machining, {}, ""))
        throw std::invalid_argument("one machining pass for " + o.c.origin + " and " + c.origin + ": their cases machine different parts");
    part.model = std::make_unique<PartModel>(build_part(c));
    const auto& mesh = part.model->mesh;
    const auto& shape = part.model->shape;
    part.clamped = clamp_dofs(c, *part.model);
    try {
      part.target = fem::target_surface_nodes(mesh, shape, {c.pocket_x, c.pocket_x + c.pocket_length_x, c.pocket_y, c.pocket_y + c.pocket_length_y,
                                                            shape.thickness() - c.pocket_depth});
    } catch (const std::invalid_argument& e) {
      throw InputError(c.origin + ": mesh.nz: " + e.what());
    }
    // The stock's top face, all of it: where the tool has not been, a laser reads it, and its w is an
    // absolute measurement (not a difference since a cut, as on the floor).
    part.top = fem::target_surface_nodes(mesh, shape, {0, shape.length_u(), 0, shape.length_v(), shape.thickness()});
    for (auto& o : pass.outputs) {
      o.profiles = o.truth ? std::vector<fem::StressProfile>{part.model->truth_profile} : fem::unit_profiles(part.model->degrees);
      o.first = static_cast<Eigen::Index>(part.profiles.size());
      part.profiles.insert(part.profiles.end(), o.profiles.begin(), o.profiles.end());
      part.groups.push_back(static_cast<int>(o.profiles.size()));
      o.mode = o.truth ? "truth" : "offline";
      o.case_hash = fnv1a(o.c.resolved_toml);
    }
  });
  return part;
}

// The shared checkpoint folder: rank 0 opens (or starts) it, the other ranks join it after. Rows per
// station: the target's nodes, then the top's ("+top+key": checkpoints of older runs are not mixed in).
void open_checkpoints(const Pass& pass) {
  auto open = [&](Checkpoint::Join join) {
    for (auto& o : pass.outputs)
      o.checkpoint = std::make_unique<Checkpoint>(o.options.out / ".checkpoint", o.mode + "+top+key " + hex(o.case_hash) + "\n", join);
  };
  const Checkpoint::Join join = pass.options.merge ? Checkpoint::Join::Existing
                                : !pass.options.stations.empty() ? Checkpoint::Join::Shared
                                : pass.options.resume ? Checkpoint::Join::Resume
                                                      : Checkpoint::Join::Fresh;
  on_root_then_broadcast(pass.team, [&] {
    for (const auto& o : pass.outputs) {
      check_output_folder(o.options.out);
      // A new job: the earlier one's database and summary go first (support/summary.hpp).
      if (join != Checkpoint::Join::Existing && !std::filesystem::exists(o.options.out / ".checkpoint" / "manifest.txt")) clear_earlier_run(o.options.out, o.mode);
    }
    open(join);
    return std::string();
  });
  on_every_rank(pass.team, [&] {
    if (!pass.team.root()) open(Checkpoint::Join::Existing);
  });
}

// 1. Removal, on rank 0 (`run` is rank 0's): the activity of every station (level set, a few seconds),
//    as what changes from one station to the next; every rank replays it.
// A stop asked outside the station sweep (JobOptions::stop) throws StopRequested; run_job turns it
// into an unfinished result. Nothing the job saved is lost: the checkpoints are written per station.
void stop_if_asked(const Pass& pass) { throw_if_stop_requested(pass.options.stop); }

ActivityHistory sweep_removal(const Pass& pass, const PartModel& part, std::unique_ptr<MachiningRun>& run) {
  return ActivityHistory::from_bytes(on_root_then_broadcast(pass.team, [&] {
    run = std::make_unique<MachiningRun>(pass.c, part);
    ActivityHistory swept(static_cast<std::size_t>(part.mesh.element_count()));
    std::vector<double> remaining(static_cast<std::size_t>(part.mesh.element_count()), 1.0);
    for (std::size_t k = 0; k < run->stations().size(); ++k) {
      stop_if_asked(pass);
      run->advance(remaining);
      swept.append(remaining);
    }
    return swept.bytes();
  }), "rank 0's removal");
}

void announce_pass(const Pass& pass, const PassPart& part, std::size_t ns, double removal_seconds) {
  const auto P = static_cast<Eigen::Index>(part.profiles.size());
  if (!pass.quiet)
    std::cerr << "drom " << pass.modes() << ": " << pass.c.name << ": " << ns << " stations, " << part.model->mesh.dof_count() << " unknowns, " << P
              << " profile" << (P > 1 ? "s" : "") << ", " << part.target.size() << " target-surface nodes (removal " << removal_seconds << " s)"
              << (pass.team.size() > 1 ? ", " + std::to_string(pass.team.size()) + " ranks" : "") << "\n";
}

StationRange station_range(const Pass& pass, std::size_t ns) {
  StationRange range{0, ns};
  on_every_rank(pass.team, [&] {
    if (!pass.options.stations.empty()) range = parse_station_range(pass.options.stations, ns, "--stations");
  });
  return range;
}

struct Equilibrium {
  std::unique_ptr<StationSolvers> solvers;
  nlohmann::json chunk_plan;
};

// 2. Equilibrate once, on rank 0; every rank adopts it, and every worker from its rank.
Equilibrium equilibrate(const Pass& pass, const PassPart& part, const ActivityHistory& history) {
  Equilibrium e;
  const std::string equilibrium = on_root_then_broadcast(pass.team, [&] {
    e.solvers = StationSolvers::create(pass.c, *part.model, part.profiles, part.clamped, part.groups);
    return e.solvers->equilibrium();
  });
  on_every_rank(pass.team, [&] {
    if (!pass.team.root()) e.solvers = StationSolvers::create(pass.c, *part.model, part.profiles, part.clamped, part.groups, equilibrium);
    // Every rank from the same history and pattern: the same chunks everywhere.
    e.chunk_plan = e.solvers->plan(history);
  });
  return e;
}

// drom merge's refusal: the missing stations as ranges, each with the slice that should have saved it.
std::string missing_stations(const Checkpoint& checkpoint, const std::vector<std::size_t>& missing) {
  std::string list;
  for (std::size_t i = 0; i < missing.size();) {
    std::size_t j = i;
    while (j + 1 < missing.size() && missing[j + 1] == missing[j] + 1) ++j;
    if (list.size() > 400) {
      list += ", ...";
      break;
    }
    list += (list.empty() ? "" : ", ") + to_string(StationRange{missing[i], missing[j] + 1}) + checkpoint.slice_holding(missing[i]);
    i = j + 1;
  }
  return list;
}

// This rank's share of the stations still missing.
struct Deal {
  std::size_t done_before = 0;        // stations every output had saved before this run
  std::size_t measured_stations = 0;  // of those, the ones whose solve time calibrated the costs (rank 0's count)
  std::vector<ChunkTask> mine;
};

void read_deal(const std::string& dealt, const JobTeam& team, Deal& deal) {
  ByteReader r(dealt, "rank 0's schedule");
  deal.done_before = r.get<std::uint64_t>();
  for (int rank = 0; rank < team.size(); ++rank) {
    const auto count = r.get<std::uint64_t>();
    for (std::uint64_t i = 0; i < count; ++i) {
      ChunkTask t;
      t.first = r.get<std::uint64_t>();
      t.last = r.get<std::uint64_t>();
      t.cost = r.get<double>();
      if (rank == team.rank()) deal.mine.push_back(t);
    }
  }
}

// 3. The stations still missing, dealt out by rank 0 in contiguous blocks of chunks (a warm-starting
//    solver's chunk is solved in order from its first station), balanced by their estimated cost:
//    the cost law calibrated on the solve times the stations already saved measured.
Deal deal_stations(const Pass& pass, const ActivityHistory& history, const StationSolvers& solvers, const StationRange& range) {
  const std::size_t ns = history.stations();
  Deal deal;
  const std::string dealt = on_root_then_broadcast(pass.team, [&] {
    std::vector<double> measured(ns, 0.0);
    std::vector<std::size_t> missing;
    for (std::size_t k = 0; k < ns; ++k) {
      if (pass.saved_by_all(station_name(k))) {
        ++deal.done_before;
        measured[k] = pass.outputs.front().checkpoint->seconds(station_name(k));
        deal.measured_stations += measured[k] > 0;
      } else {
        missing.push_back(k);
      }
    }
    if (pass.options.merge && !missing.empty())
      throw InputError((pass.outputs.front().options.out / ".checkpoint").string() + ": " + std::to_string(missing.size()) + " of " +
                       std::to_string(ns) + " stations are missing, stations " + missing_stations(*pass.outputs.front().checkpoint, missing) +
                       " (a:b is stations a to b - 1); run them with --stations a:b, then merge again");
    const auto tasks = chunk_tasks(ns, solvers.chunk(), [&](std::size_t k) { return range.contains(k) && !pass.saved_by_all(station_name(k)); },
                                   calibrated_costs(station_costs(history), measured));
    const auto blocks = deal_blocks(tasks, pass.team.size(), 0);
    ByteWriter w;
    w.put<std::uint64_t>(deal.done_before);
    for (const auto& block : blocks) {
      w.put<std::uint64_t>(block.size());
      for (const auto& t : block) w.put<std::uint64_t>(t.first), w.put<std::uint64_t>(t.last), w.put(t.cost);
    }
    return w.take();
  });
  read_deal(dealt, pass.team, deal);
  return deal;
}

void choose_frames(std::vector<Output>& outputs, std::size_t ns) {
  for (auto& o : outputs) {
    const int wanted = o.options.frames >= 0 ? o.options.frames : (o.truth ? 10 : 0);
    o.frames = static_cast<std::size_t>(std::min<int>(wanted, static_cast<int>(ns)));
  }
}

// A --stations run's record in every output's checkpoint folder (none for a whole job).
void record_slice_state(const Pass& pass, const StationRange& range, bool finished, std::size_t saved) {
  if (pass.options.stations.empty()) return;
  const nlohmann::json record{{"stations", to_string(range)}, {"first", range.first}, {"last", range.last},
                              {"host", host_name()}, {"ranks", pass.team.size()},
                              {"finished", finished}, {"stations_saved_by_this_run", saved}};
  for (const auto& o : pass.outputs) o.checkpoint->record_slice(range, record);
}

NamedDisplacements named_displacements(const Output& o, const Eigen::MatrixXd& U) {
  NamedDisplacements named;
  if (o.truth) named.emplace_back("displacement", U.col(o.first));
  for (Eigen::Index p = 0; !o.truth && p < o.count(); ++p) named.emplace_back(profile_name(o.profiles[static_cast<std::size_t>(p)]), U.col(o.first + p));
  return named;
}

// This rank's chunks, solved by `threads` workers with a solver each; every station not saved yet
// goes to each output's checkpoint (and frame).
struct StationSweep {
  const Pass& pass;
  const PassPart& part;
  const ActivityHistory& history;
  const StationSolvers& solvers;
  const StationRange& range;
  const Deal& deal;
  int threads = 1;
  double removal_seconds = 0, equilibrium_seconds = 0;  // before the solves: the rate counts from their end

  std::mutex report{};  // one progress report at a time, and the statistics
  std::atomic<std::size_t> next{0};
  std::atomic<int> solved{0};
  StationWork work{};
  nlohmann::json statistics = nlohmann::json::object();  // the workers' solver figures, summed

  void run();
  void worker();
  bool solve_chunk(StationSolver& solver, const ChunkTask& task, std::vector<double>& activity);
  void save_station(const StationSolver& solver, std::size_t k, const Eigen::MatrixXd& U, double solve_seconds) const;
  void print_progress(std::size_t done) const;
};

void StationSweep::print_progress(std::size_t done) const {
  const std::size_t ns = history.stations();
  const bool report_now = pass.interactive || done % std::max<std::size_t>(1, ns / 50) == 0 || done == ns;
  if (pass.quiet || !report_now) return;
  const double rate = static_cast<double>(done - deal.done_before) / std::max(1e-9, pass.elapsed() - removal_seconds - equilibrium_seconds);
  std::fprintf(stderr, "%s  station %zu/%zu  %.2f stations/s  %.0f s left%s", pass.interactive ? "\r" : "", done, ns, rate,
               static_cast<double>(ns - done) / std::max(1e-9, rate), pass.interactive ? "   " : "\n");
}

void StationSweep::save_station(const StationSolver& solver, std::size_t k, const Eigen::MatrixXd& U, double solve_seconds) const {
  const std::vector<int>& target = part.target;
  const std::vector<int>& top = part.top;
  for (const auto& o : pass.outputs) {
    if (o.checkpoint->has(station_name(k))) continue;
    Eigen::MatrixXd W(static_cast<Eigen::Index>(target.size() + top.size()), o.count());
    for (std::size_t i = 0; i < target.size(); ++i) W.row(static_cast<Eigen::Index>(i)) = U.row(3 * target[i] + 2).segment(o.first, o.count());
    for (std::size_t i = 0; i < top.size(); ++i)
      W.row(static_cast<Eigen::Index>(target.size() + i)) = U.row(3 * top[i] + 2).segment(o.first, o.count());
    if (frame_at(k, history.stations(), o.frames))
      solver.write_vtu(o.options.out / "frames" / (station_name(k) + ".vtu"), named_displacements(o, U), static_cast<std::size_t>(o.first));
    o.checkpoint->save(station_name(k), W, solve_seconds);
  }
}

// False when the sweep must stop here (cancelled, or --stop-after reached).
bool StationSweep::solve_chunk(StationSolver& solver, const ChunkTask& task, std::vector<double>& activity) {
  const std::size_t ns = history.stations();
  // A chunk restarts from its first station (cold), so a resumed run solves exactly what an
  // uninterrupted one does; finished stations are recomputed but not written again.
  activity = history.at(task.first);
  // The whole chunk's changes, also where a slice or a resume solves only part of it: the same
  // block, so the same round-off.
  if (solvers.chunk() > 1)
    solver.start_chunk(history.run_changes(task.first, std::min(ns, task.first + solvers.chunk()), fem::ElasticProblem::kMinVolumeFraction));
  for (std::size_t k = task.first; k < task.last; ++k) {
    if (k > task.first) history.advance(k, activity);
    const bool saved = !range.contains(k) || pass.saved_by_all(station_name(k));
    if (!saved && (work.cancelled() || pass.options.stop.stop_requested() || (pass.options.stop_after >= 0 && solved.fetch_add(1) >= pass.options.stop_after))) return false;
    const auto solve_start = std::chrono::steady_clock::now();
    const Eigen::MatrixXd U = solver.solve(activity, k > task.first);
    const double solve_seconds = seconds_since(solve_start);
    if (saved) continue;
    save_station(solver, k, U, solve_seconds);
    const std::size_t saved_here = work.saved_one();
    if (pass.team.reports_per_station()) {
      std::lock_guard<std::mutex> lock(report);
      print_progress(deal.done_before + saved_here);
      if (pass.options.progress && !pass.options.progress(deal.done_before + saved_here, ns)) work.cancel();
    }
  }
  return true;
}

void StationSweep::worker() {
  try {
    // Again here: OpenMP's max-active-levels is kept per thread, so a worker thread starts with
    // CHOLMOD's teams of four (measured: 22 % of a PGD run's CPU time went to the system, 36 000
    // futex calls a second).
    const SingleThreadedKernels worker_kernels;
    const auto solver = solvers.make_worker();
    bool stopped = false;
    std::vector<double> activity;
    for (std::size_t j = next++; j < deal.mine.size() && !stopped && !work.cancelled() && !pass.options.stop.stop_requested(); j = next++)
      stopped = !solve_chunk(*solver, deal.mine[j], activity);
    std::lock_guard<std::mutex> lock(report);
    accumulate(statistics, solver->statistics());
  } catch (...) {
    work.fail(std::current_exception());
  }
  work.worker_done();
}

void StationSweep::run() {
  std::vector<std::thread> pool;
  work.start(threads);
  for (int t = 0; t < threads; ++t) pool.emplace_back([this] { worker(); });
  try {
    // Rank 0 reports the whole job's progress (several ranks: a few times a second).
    pass.team.supervise(work, [&](std::size_t saved) {
      print_progress(deal.done_before + saved);
      return !pass.options.progress || pass.options.progress(deal.done_before + saved, history.stations());
    });
  } catch (...) {
    work.cancel();
    for (auto& t : pool) t.join();
    throw;
  }
  for (auto& t : pool) t.join();
  if (!pass.quiet && pass.interactive) std::cerr << "\n";
}

// What each output's database is written from, beside its own checkpoints.
struct DatabaseSources {
  const Pass& pass;
  const PartModel& part;
  const std::vector<int>& target;
  const std::vector<int>& top;
  const std::vector<levelset::Station>& stations;
  const levelset::Toolpath& path;
  const std::vector<double>& final_activity;
  double removal_seconds = 0;
  const nlohmann::json& figures;  // the pass's, shared by its outputs
};

// The snapshot matrices, row-major as the database stores them.
struct Snapshots {
  std::vector<double> B1, B1_top, B2;
  std::size_t B2_rows = 0;
};

Snapshots load_snapshots(const Output& o, std::size_t ns, std::size_t nt, std::size_t ntop) {
  const Eigen::Index P = o.count();
  const auto Pu = static_cast<std::size_t>(P);
  Snapshots s;
  s.B1.resize(ns * nt * Pu);
  s.B1_top.resize(ns * ntop * Pu);
  for (std::size_t k = 0; k < ns; ++k) {
    const Eigen::MatrixXd W = o.checkpoint->load(station_name(k), k);
    if (W.rows() != static_cast<Eigen::Index>(nt + ntop) || W.cols() != P) throw InputError(o.checkpoint->file(station_name(k)).string() + ": not this run's station");
    for (std::size_t i = 0; i < nt; ++i)
      for (Eigen::Index p = 0; p < P; ++p) s.B1[(k * nt + i) * Pu + static_cast<std::size_t>(p)] = W(static_cast<Eigen::Index>(i), p);
    for (std::size_t i = 0; i < ntop; ++i)
      for (Eigen::Index p = 0; p < P; ++p) s.B1_top[(k * ntop + i) * Pu + static_cast<std::size_t>(p)] = W(static_cast<Eigen::Index>(nt + i), p);
  }
  const Eigen::MatrixXd U2 = o.checkpoint->load("final", ns);
  s.B2.resize(static_cast<std::size_t>(U2.size()));
  for (Eigen::Index r = 0; r < U2.rows(); ++r)
    for (Eigen::Index p = 0; p < P; ++p) s.B2[static_cast<std::size_t>(r * P + p)] = U2(r, p);
  s.B2_rows = static_cast<std::size_t>(U2.rows());
  return s;
}

std::uint64_t content_hash(const Output& o, const Snapshots& s) {
  std::uint64_t content = fnv1a(s.B1.data(), s.B1.size() * sizeof(double), o.case_hash);
  content = fnv1a(s.B2.data(), s.B2.size() * sizeof(double), content);
  return fnv1a(s.B1_top.data(), s.B1_top.size() * sizeof(double), content);
}

// Per unit profile: its direction (11 or 22) and its degree.
std::vector<double> unit_profile_rows(const Output& o) {
  std::vector<double> unit(2 * static_cast<std::size_t>(o.count()));
  for (Eigen::Index p = 0; p < o.count(); ++p) {
    const auto& prof = o.profiles[static_cast<std::size_t>(p)];
    for (std::size_t j = 0; j < prof.degrees.size(); ++j) {
      if (prof.sigma11[j] != 0) unit[2 * static_cast<std::size_t>(p)] = 11, unit[2 * static_cast<std::size_t>(p) + 1] = prof.degrees[j];
      if (prof.sigma22[j] != 0) unit[2 * static_cast<std::size_t>(p)] = 22, unit[2 * static_cast<std::size_t>(p) + 1] = prof.degrees[j];
    }
  }
  return unit;
}

void write_database_file(const Output& o, const DatabaseSources& in, const Snapshots& s, std::uint64_t content) {
  const auto& mesh = in.part.mesh;
  const std::size_t ns = in.stations.size(), nt = in.target.size(), ntop = in.top.size();
  const auto P = static_cast<std::size_t>(o.count());
  std::vector<double> target_xyz(3 * nt), target_ids(nt), nodes(3 * static_cast<std::size_t>(mesh.node_count()));
  for (std::size_t i = 0; i < nt; ++i) {
    target_ids[i] = in.target[i];
    for (int d = 0; d < 3; ++d) target_xyz[3 * i + static_cast<std::size_t>(d)] = mesh.nodes[static_cast<std::size_t>(in.target[i])][d];
  }
  std::vector<double> top_ids(in.top.begin(), in.top.end());
  for (int n = 0; n < mesh.node_count(); ++n)
    for (int d = 0; d < 3; ++d) nodes[3 * static_cast<std::size_t>(n) + static_cast<std::size_t>(d)] = mesh.nodes[static_cast<std::size_t>(n)][d];
  std::vector<double> connectivity(mesh.connectivity.begin(), mesh.connectivity.end());
  Hdf5Writer h5(o.options.out / "database.h5");
  write_file_format(h5, kSnapshotDatabase);
  h5.write("B1", s.B1, ns * nt, P);
  h5.write("B2", s.B2, s.B2_rows, P);
  h5.write("B1_top", s.B1_top, ns * ntop, P);
  h5.write("top_nodes", top_ids, ntop, 1);
  write_stations(h5, in.stations);
  h5.write("target_nodes", target_ids, nt, 1);
  h5.write("target_coordinates", target_xyz, nt, 3);
  h5.write("node_coordinates", nodes, static_cast<std::size_t>(mesh.node_count()), 3);
  h5.write("connectivity", connectivity, static_cast<std::size_t>(mesh.element_count()), static_cast<std::size_t>(fem::nodes_per_element(mesh.type)));
  h5.write("final_activity", in.final_activity, in.final_activity.size(), 1);
  if (o.truth) {
    const auto& truth_profile = in.part.truth_profile;
    std::vector<double> coefficients(truth_profile.sigma11);
    coefficients.insert(coefficients.end(), truth_profile.sigma22.begin(), truth_profile.sigma22.end());
    h5.write("profile_coefficients", coefficients, 2, truth_profile.degrees.size());
  } else {
    h5.write("unit_profiles", unit_profile_rows(o), P, 2);
  }
  const auto& written_degrees = o.truth ? in.part.truth_profile.degrees : in.part.degrees;
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
  write_reduction_inputs(h5, o.c, in.part, in.target, in.top, in.path, in.final_activity);
  h5.commit();
}

void write_frames_pvd(const Output& o, const std::vector<levelset::Station>& stations) {
  const std::size_t ns = stations.size();
  fem::PvdCollection pvd;
  for (std::size_t k = 0; k < ns; ++k)
    if (frame_at(k, ns, o.frames)) pvd.add(stations[k].time, std::filesystem::path("frames") / (station_name(k) + ".vtu"));
  pvd.write(o.options.out / (o.mode + ".pvd"));
}

nlohmann::json database_summary(const Output& o, const DatabaseSources& in, const Snapshots& s, std::uint64_t content) {
  const std::size_t ns = in.stations.size();
  double max_w = 0;
  for (double v : s.B1) max_w = std::max(max_w, std::abs(v));
  const auto db_size = std::filesystem::file_size(o.options.out / "database.h5");
  nlohmann::json summary{{"command", o.mode},
                         {"case", o.c.name},
                         {"stations", ns},
                         {"unknowns", in.part.mesh.dof_count()},
                         {"profiles", o.count()},
                         {"target_nodes", in.target.size()},
                         {"top_nodes", in.top.size()},
                         {"time_s", in.pass.elapsed()},
                         {"removal_time_s", in.removal_seconds},
                         {"time_per_station_s", (in.pass.elapsed() - in.removal_seconds) / static_cast<double>(ns)},
                         {"peak_memory_mb", static_cast<double>(peak_memory_bytes()) / 1048576.0},
                         {"database_mb", static_cast<double>(db_size) / 1048576.0},
                         {"max_abs_B1_mm", max_w},
                         {"case_hash", hex(o.case_hash)},
                         {"content_hash", hex(content)},
                         {"machine", machine_info()},
                         {"frames", o.frames},
                         {"files", o.frames > 0 ? nlohmann::json{"database.h5", o.mode + ".pvd", "frames/", "final_free_shape.vtu"}
                                             : nlohmann::json{"database.h5", "final_free_shape.vtu"}}};
  summary.update(in.figures);
  return summary;
}

// Step 5 of simulate for one output: its database from its checkpoints (so a resumed run writes the
// same bytes), its frames' .pvd and its summary.json.
nlohmann::json write_database(const Output& o, const DatabaseSources& in) {
  const Snapshots snapshots = load_snapshots(o, in.stations.size(), in.target.size(), in.top.size());
  const std::uint64_t content = content_hash(o, snapshots);
  write_database_file(o, in, snapshots, content);
  if (o.frames > 0) write_frames_pvd(o, in.stations);
  const nlohmann::json summary = database_summary(o, in, snapshots, content);
  write_summary(o.options.out, summary);
  o.checkpoint->remove();  // last: a job stopped before this resumes from its stations and writes all again
  return summary;
}

// What the end of the pass needs from its stages.
struct PassEnd {
  const Pass& pass;
  const PassPart& part;
  const ActivityHistory& history;
  const StationSolvers& solvers;
  const MachiningRun* run = nullptr;  // rank 0's
  const StationRange& range;
  std::size_t saved_by_this_run = 0;
  int threads = 1;
  const nlohmann::json& chunk_plan;
  double removal_seconds = 0, equilibrium_seconds = 0;
  std::size_t measured_stations = 0;
};

// 4. The free final shape (best-fit alignment, one column per profile), into every output's checkpoint.
void solve_final_shape(const PassEnd& end, const std::vector<double>& final_activity, nlohmann::json& solver_statistics) {
  const auto solver = end.solvers.make_worker();
  const auto solve_start = std::chrono::steady_clock::now();
  const Eigen::MatrixXd U = solver->free_shape(final_activity);
  const double solve_seconds = seconds_since(solve_start);
  accumulate(solver_statistics, {{"final_shape", solver->statistics()}});
  for (const auto& o : end.pass.outputs) {
    if (o.checkpoint->has("final")) continue;
    solver->write_vtu(o.options.out / "final_free_shape.vtu", named_displacements(o, U), static_cast<std::size_t>(o.first));
    o.checkpoint->save("final", U.middleCols(o.first, o.count()), solve_seconds);
  }
}

// 4. and 5., on rank 0: the final shape and each database once every station is saved, from the
// checkpoints (so a resumed or distributed run writes the same bytes). Returns the stations saved and
// the databases' summaries.
nlohmann::json finish_on_root(const PassEnd& end, nlohmann::json& solver_statistics) {
  const Pass& pass = end.pass;
  const std::size_t ns = end.history.stations();
  const StationRange& range = end.range;
  std::size_t finished = 0;
  for (std::size_t k = 0; k < ns; ++k) finished += pass.saved_by_all(station_name(k));
  nlohmann::json all = nlohmann::json::array();
  if (!pass.options.stations.empty()) {
    std::size_t in_range = 0;
    for (std::size_t k = range.first; k < range.last; ++k) in_range += pass.saved_by_all(station_name(k));
    record_slice_state(pass, range, in_range == range.size(), end.saved_by_this_run);
    if (!pass.quiet)
      std::cerr << "drom " << pass.modes() << ": slice " << to_string(range) << ": " << in_range << " of " << range.size() << " stations saved; "
                << finished << " of " << ns << " in the job" << (finished == ns ? ": drom merge writes the database\n" : "\n");
    return nlohmann::json{{"saved", finished}, {"summaries", all}};
  }
  if (finished < ns) {
    if (!pass.quiet) std::cerr << "drom " << pass.modes() << ": stopped after " << finished << " of " << ns << " stations; continue with --resume\n";
    return nlohmann::json{{"saved", finished}, {"summaries", all}};
  }
  const std::vector<double> final_activity = end.history.at(ns - 1);
  if (!pass.saved_by_all("final")) solve_final_shape(end, final_activity, solver_statistics);
  const nlohmann::json figures{{"threads", end.threads},
                               {"ranks", pass.team.size()},
                               {"solver", pass.c.solver},
                               {"solver_statistics", solver_statistics},
                               {"equilibrium", end.solvers.equilibrium_statistics()},
                               {"chunk_plan", end.chunk_plan},
                               {"equilibrium_time_s", end.equilibrium_seconds},
                               {"deal_measured_stations", end.measured_stations},
                               {"pass_outputs", pass.modes()}};
  const DatabaseSources sources{.pass = pass,
                                .part = *end.part.model,
                                .target = end.part.target,
                                .top = end.part.top,
                                .stations = end.run->stations(),
                                .path = end.run->path(),
                                .final_activity = final_activity,
                                .removal_seconds = end.removal_seconds,
                                .figures = figures};
  for (const auto& o : pass.outputs) all.push_back(write_database(o, sources));
  return nlohmann::json{{"saved", finished}, {"summaries", all}};
}

// Every rank's results, from rank 0's outcome.
std::vector<JobResult> job_results(const std::string& outcome_text, std::size_t outputs, std::size_t ns) {
  const auto outcome = nlohmann::json::parse(outcome_text);
  std::vector<JobResult> results(outputs);
  for (std::size_t i = 0; i < results.size(); ++i) {
    results[i].stations = ns;
    results[i].stations_saved = outcome["saved"].get<std::size_t>();
    results[i].finished = i < outcome["summaries"].size();
    if (results[i].finished) results[i].summary = outcome["summaries"][i];
  }
  return results;
}

// The machining simulation, once for all `outputs` (one factorization per station serves them all);
// each output's database is what a pass of its own would write, bit for bit. With several ranks
// (offline/job_team.hpp), rank 0 sweeps the removal and equilibrates the stock, every rank solves
// its block of stations, and rank 0 writes the databases: the same bytes, whatever the ranks.
std::vector<JobResult> simulate(std::vector<Output>& outputs) {
  const auto start = std::chrono::steady_clock::now();
  const JobOptions& options = outputs.front().options;  // quiet, threads, stop_after, progress, stations, merge, team
  SoloTeam solo;
  JobTeam& team = options.team ? *options.team : solo;
  const Pass pass{.outputs = outputs,
                  .options = options,
                  .team = team,
                  .c = machined_case(outputs),
                  .quiet = options.quiet || !team.root(),
                  .interactive = isatty(2) != 0,
                  .start = start};
  const PassPart part = prepare_part(pass);
  open_checkpoints(pass);
  std::unique_ptr<MachiningRun> run;
  const ActivityHistory history = sweep_removal(pass, *part.model, run);
  const std::size_t ns = history.stations();
  const double removal_seconds = pass.elapsed();
  announce_pass(pass, part, ns, removal_seconds);
  const StationRange range = station_range(pass, ns);

  // Station workers fill the cores; threads inside each factorization would fight them (measured: a
  // third of the run in system time). Single-threaded kernels also round the same way whatever
  // --threads is, so the database does not depend on it.
  const SingleThreadedKernels single_threaded_kernels;
  stop_if_asked(pass);
  const Equilibrium equilibrium = equilibrate(pass, part, history);
  stop_if_asked(pass);
  const double equilibrium_seconds = pass.elapsed() - removal_seconds;
  const Deal deal = deal_stations(pass, history, *equilibrium.solvers, range);
  const int threads = options.threads > 0 ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  choose_frames(outputs, ns);
  on_root_then_broadcast(team, [&] {
    record_slice_state(pass, range, false, 0);
    return std::string();
  });
  StationSweep sweep{.pass = pass,
                     .part = part,
                     .history = history,
                     .solvers = *equilibrium.solvers,
                     .range = range,
                     .deal = deal,
                     .threads = threads,
                     .removal_seconds = removal_seconds,
                     .equilibrium_seconds = equilibrium_seconds};
  sweep.run();
  // Every rank's solver figures, summed on rank 0.
  const auto figures = team.gather(sweep.statistics.dump());
  for (std::size_t r = 1; r < figures.size(); ++r) accumulate(sweep.statistics, nlohmann::json::parse(figures[r]));

  const PassEnd end{.pass = pass,
                    .part = part,
                    .history = history,
                    .solvers = *equilibrium.solvers,
                    .run = run.get(),
                    .range = range,
                    .saved_by_this_run = sweep.work.saved(),
                    .threads = threads,
                    .chunk_plan = equilibrium.chunk_plan,
                    .removal_seconds = removal_seconds,
                    .equilibrium_seconds = equilibrium_seconds,
                    .measured_stations = deal.measured_stations};
  const std::string outcome = on_root_then_broadcast(team, [&] { return finish_on_root(end, sweep.statistics).dump(); });
  return job_results(outcome, outputs.size(), ns);
}

}  // namespace

// simulate(), with a stop asked before the station sweep as an unfinished result (in the sweep,
// the workers stop and the pass ends as with --stop-after).
std::vector<JobResult> simulate_until_stopped(std::vector<Output>& outputs) {
  try {
    return simulate(outputs);
  } catch (const StopRequested&) {
    if (!outputs.front().options.quiet) std::cerr << "drom: stopped on request before the stations; continue with --resume\n";
    return std::vector<JobResult>(outputs.size());
  }
}

JobResult run_job(const case_file::Case& c, JobKind kind, const JobOptions& options) {
  std::vector<Output> outputs(1);
  outputs[0].options = options;
  outputs[0].truth = kind == JobKind::Truth;
  outputs[0].c = c;
  return simulate_until_stopped(outputs).front();
}

std::pair<JobResult, JobResult> run_offline_and_truth(const case_file::Case& offline_case, const JobOptions& offline, const case_file::Case& truth_case,
                                                      const JobOptions& truth) {
  std::vector<Output> outputs(2);
  outputs[0].options = offline;
  outputs[0].c = offline_case;
  outputs[1].options = truth;
  outputs[1].truth = true;
  outputs[1].c = truth_case;
  auto results = simulate_until_stopped(outputs);
  return {results[0], results[1]};
}

}  // namespace drom::offline
