#pragma once
// What drom run and drom study share: the case at the run's scale, the offline database, the light
// model and the truth run under --out (each computed once and reused while the case that made it is
// unchanged), and the closed loop's settings from the case.
#include "case_file/case.hpp"
#include "geometry/part_shape.hpp"
#include "offline/job_team.hpp"
#include "online/loop_simulation.hpp"
#include "reduce/light_model.hpp"

#include <filesystem>
#include <functional>
#include <stop_token>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace drom::loop {

// The case as drom run runs it: with [run] scale = "quick", run.quick's overrides first, then the
// user's (so --set wins).
case_file::Case load_run_case(const std::optional<std::filesystem::path>& path, const std::vector<std::string>& overrides);

// Where and how drom run and drom study work.
struct RunOptions {
  std::filesystem::path out = "out";  // offline/, truth/ and model/ are kept here and reused
  bool quiet = false;                 // no progress on stderr
  int threads = 0;                    // the offline job's workers; 0: one per hardware thread
  bool replan = false;                // re-plan a finishing pass on the predicted final shape (loop/replanned_finish.hpp)
  // The ranks of an MPI job (mpirun -np N drom run): they share the offline-and-truth pass, then rank 0
  // alone goes on. Null: this process alone.
  offline::JobTeam* team = nullptr;
  // A stop asked from outside (Python's Ctrl-C): the stages stop as the offline job does
  // (JobOptions::stop), the loop within a percent of its steps; then StopRequested is thrown
  // (support/stop_request.hpp), and a rerun resumes the stages from their checkpoints.
  std::stop_token stop;
  // The command whose folder `out` is ("run", "study"): before the stages, on rank 0 and so within
  // the team's first collective step, the folder is checked, the [sync] machine read, and the
  // earlier run's outputs cleared (support/summary.hpp). Empty: the stages alone, nothing cleared.
  std::string command;
};

// The truth run, as the closed loop plays it.
struct TruthRun {
  Eigen::MatrixXd target_history;        // target nodes x stations (mm)
  Eigen::MatrixXd top_history;           // the model's top nodes x stations (mm), held after each node's cut; empty without a top
  Eigen::VectorXd station_times;
  Eigen::Matrix3Xd final_displacement;   // at the model's final-shape nodes
  double amplitude = 1;                  // the case's truth.amplitude it was computed with
};

// One loop's own copy of the truth (a SurfaceHistory caches, so loops in parallel each need one).
struct TruthPlay {
  std::unique_ptr<online::SurfaceHistory> history, top_history;
  online::TruePart part;
};

struct ClosedLoopInputs {
  reduce::LightModel model;
  TruthRun truth;
  geometry::PartShape shape;
  // The truth with its stresses multiplied by `factor` (displacements are linear in them).
  TruthPlay play(double factor = 1) const;
  double offline_seconds = 0, truth_seconds = 0, reduce_seconds = 0;  // this invocation's
  bool one_pass = false;  // offline and truth computed in one machining pass (its time in offline_seconds)
  bool reused_offline = false, reused_truth = false;
};

// Runs (or reuses) out/offline, out/model and out/truth for the case. Progress on stderr unless quiet.
// With options.team, this is rank 0's part; the other ranks call help_prepare_closed_loop.
ClosedLoopInputs prepare_closed_loop(const case_file::Case& c, const RunOptions& options);
// A rank after rank 0 of an MPI drom run: its share of the machining pass that prepare_closed_loop
// runs on rank 0, nothing else.
void help_prepare_closed_loop(const case_file::Case& c, const RunOptions& options);

// The case's [sync] machine read (InputError naming it otherwise): before the stages, so a wrong
// name costs no machining simulation.
void check_sync_machine(const case_file::Case& c);

// The measurement sigma is the sensor's noise and the model's own error bound together: a noise-free
// sensor still sees what the model cannot represent, and the band should say so.
online::PredictorSettings predictor_settings(const case_file::Case& c, const reduce::LightModel& model);
// The loop's settings; the machine's real motion along the model's path ([sync] machine) is
// predicted here (machine/program_clock.hpp).
online::LoopSimulationSettings loop_settings(const case_file::Case& c, const reduce::LightModel& model);

// The loop twice on the same case, at once on two threads: offsets commanded (corrected) and held at
// 0 (uncorrected), each on its own copy of the truth played by `factor`. `progress` gets the
// corrected loop's fraction done. A stop asked through `stop` throws StopRequested from both loops
// within a percent of their steps.
struct LoopPair {
  online::LoopSimulationResult corrected, uncorrected;
  online::LoopSimulationSettings corrected_settings;  // the corrected loop's
  TruthPlay corrected_truth;                          // the truth the corrected loop played
};
LoopPair run_both_loops(const case_file::Case& c, const ClosedLoopInputs& in, double factor, const std::stop_token& stop,
                        const std::function<void(double fraction)>& progress = {});

}  // namespace drom::loop
