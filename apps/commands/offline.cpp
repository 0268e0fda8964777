// drom offline, drom truth and drom merge: the offline job (offline/offline_job.hpp), alone or as
// one rank of an MPI job (offline/process_team.hpp).
#include "apps/commands.hpp"
#include "offline/calculix_export.hpp"
#include "offline/offline_job.hpp"
#include "support/input_error.hpp"
#include "offline/process_team.hpp"

#include <cstdio>

namespace drom::app {

namespace {

int export_ccx(const CommandOptions& options, offline::JobKind kind) {
  if (options.resume || !options.stations.empty() || options.stop_after >= 0)
    throw InputError("--export-ccx writes one station's deck: it does not combine with --resume, --stations or --stop-after");
  const auto c = case_file::load_case(options.case_path, options.overrides);
  const auto e = offline::export_calculix_station(c, kind, static_cast<std::size_t>(options.export_ccx), options.out);
  if (!options.quiet)
    std::printf("drom %s: %s: station %zu of %zu as a CalculiX deck: %d nodes, %d C3D20, %d removed, %d partly machined, %d fixed dofs (%.1f MB) -> %s\n"
                "  drom's answer (one full factorization, %.2f s): %s; max |u| %.4g mm\n  run: cd %s && ccx -i %s\n",
                kind == offline::JobKind::Truth ? "truth" : "offline", c.name.c_str(), e.station, e.stations, e.deck_stats.nodes, e.deck_stats.elements,
                e.deck_stats.removed, e.deck_stats.partial, e.deck_stats.fixed_dofs, e.deck_stats.megabytes, e.deck.string().c_str(), e.drom_solve_seconds,
                e.drom_csv.string().c_str(), e.drom_displacement.cwiseAbs().maxCoeff(), options.out.string().c_str(), e.deck.stem().string().c_str());
  return 0;
}

int job(const CommandOptions& options, offline::JobKind kind, bool merge) {
  if (options.export_ccx >= 0) return export_ccx(options, kind);
  const auto team = offline::join_launched_team();
  case_file::Case c;
  // Every rank reads the case; a bad one stops them all with the same message.
  offline::on_every_rank(*team, [&] { c = case_file::load_case(options.case_path, options.overrides); });
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
