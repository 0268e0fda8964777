// drom offline, drom truth and drom merge: the offline job (offline/offline_job.hpp), alone or as
// one rank of an MPI job (offline/process_team.hpp).
#include "apps/commands.hpp"
#include "offline/offline_job.hpp"
#include "offline/process_team.hpp"

#include <cstdio>

namespace drom::app {

namespace {

int job(const CommandOptions& options, offline::JobKind kind, bool merge) {
  const auto team = offline::join_launched_team();
  cases::Case c;
  // Every rank reads the case; a bad one stops them all with the same message.
  offline::on_every_rank(*team, [&] { c = cases::load_case(options.case_path, options.overrides); });
  offline::JobOptions o;
  o.out = options.out;
  o.resume = options.resume;
  o.stop_after = options.stop_after;
  o.threads = options.threads;
  o.frames = options.frames;
  o.quiet = options.quiet;
  o.stations = options.stations;
  o.merge = merge;
  o.team = team.get();
  const auto r = offline::run_job(c, kind, o);
  if (!options.quiet && r.finished && team->root()) {
    const auto& s = r.summary;
    std::printf("drom %s: %s: %zu stations x %d profile(s), %d unknowns, %.1f s (%.2f s per station on %d rank(s) x %d threads) -> %s/database.h5 (%.1f MB)\n",
                s["command"].get<std::string>().c_str(), c.name.c_str(), r.stations, s["profiles"].get<int>(), s["unknowns"].get<int>(), s["time_s"].get<double>(),
                s["time_per_station_s"].get<double>(), s["ranks"].get<int>(), s["threads"].get<int>(), options.out.string().c_str(),
                s["database_mb"].get<double>());
  }
  return 0;
}

}  // namespace

int offline_command(const CommandOptions& options) { return job(options, offline::JobKind::Offline, false); }
int truth_command(const CommandOptions& options) { return job(options, offline::JobKind::Truth, false); }
int merge_command(const CommandOptions& options) {
  return job(options, options.merge_kind == "truth" ? offline::JobKind::Truth : offline::JobKind::Offline, true);
}

}  // namespace drom::app
