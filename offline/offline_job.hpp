#pragma once
// The offline job (docs/design.md §5): the machining simulated station by station on the stressed part.
//   offline: one response per unit stress profile -> the snapshot database (B1: w of the target
//            surface over the stations; B1_top: the stock's top; B2: the free final shape);
//   truth:   the same for the case's own [truth] profile, with full fields: what the closed loop
//            later plays as the real part.
// Every station is checkpointed under out/.checkpoint; a job resumes where it stopped and then writes
// the same bytes as an uninterrupted one. database.h5 is written atomically at the end, with
// summary.json beside it.
//
// Example (examples/offline_job.cpp):
//   const auto c = drom::case_file::load_case("cases/curved_panel.toml", {"mesh.nx=12", "mesh.ny=12"});
//   drom::offline::JobOptions options;
//   options.out = "out/panel_db";
//   const auto result = drom::offline::run_job(c, drom::offline::JobKind::Offline, options);
#include "case_file/case.hpp"

#include <nlohmann/json.hpp>

#include <cstddef>
#include <filesystem>
#include <functional>
#include <stop_token>
#include <utility>

namespace drom::offline {

class JobTeam;

enum class JobKind { Offline, Truth };

struct JobOptions {
  std::filesystem::path out = "out";  // database.h5, summary.json, frames/ and the checkpoints
  bool resume = false;                // continue the interrupted job in `out` (refuses another case)
  int stop_after = -1;                // solve at most this many stations in this call, then stop
  int threads = 0;                    // station workers; 0: one per hardware thread
  int frames = -1;                    // full-field VTK frames over the stations; -1: 10 for truth, 0 for offline
  bool quiet = false;                 // no progress lines on stderr
  // Called after each station is saved, from a worker thread, never two at once: stations saved so
  // far, of how many. Returning false stops the job after the stations in progress (resume later).
  // An exception thrown here stops the job and comes out of run_job.
  std::function<bool(std::size_t saved, std::size_t total)> progress;
  // A stop asked from outside the job (Python's Ctrl-C, a service shutting down): the job stops as
  // when `progress` returns false, after the stations in progress, or between two steps of the
  // removal or before its next stage. It comes back unfinished, its checkpoints resumable. Each
  // check is a flag read, so a stop lands within one station's solve.
  std::stop_token stop;
  // Only the stations a:b (Python's slice: a to b - 1) into the shared checkpoint folder, for
  // schedulers without MPI; no database (drom merge writes it once every slice is there).
  std::string stations;
  // drom merge: every station must be in the checkpoint folder already (else InputError naming the
  // missing ones and the slices that should have made them); then the final shape and the database.
  bool merge = false;
  // The ranks running this job together (offline/process_team.hpp); null: this process alone. With
  // several, rank 0 prints, calls `progress` for the whole job and writes the files; stop_after
  // counts per rank; the other ranks' results hold the job's outcome, not its files.
  JobTeam* team = nullptr;
};

struct JobResult {
  bool finished = false;  // every station solved and database.h5 written
  std::size_t stations = 0, stations_saved = 0;
  nlohmann::json summary;  // what summary.json holds (empty unless finished)
};

// Runs (or resumes) the job for the case. Throws InputError for bad input (a case whose mesh cannot
// hold its pocket, a checkpoint of another case in `out`, ...).
JobResult run_job(const case_file::Case& c, JobKind kind, const JobOptions& options);

// Both databases in one machining pass (drom run): one factorization per station serves the unit
// profiles and the truth, and each database is the one run_job writes for it, bit for bit. The two
// cases must machine the same part: they may differ by [truth] and the closed loop's tables only.
// stop_after, threads, quiet, progress and stop are taken from the offline job's options.
std::pair<JobResult, JobResult> run_offline_and_truth(const case_file::Case& offline_case, const JobOptions& offline, const case_file::Case& truth_case,
                                                      const JobOptions& truth);

}  // namespace drom::offline
