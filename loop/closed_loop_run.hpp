#pragma once
// The closed loop on a case (drom run), the seed's §3.5 experiment:
//   1. offline snapshots of the basis's unit profiles, and the light model (offline/, reduce/);
//   2. the truth: the same machining with the [truth] profile, outside the basis;
//   3. the loop twice on the same sensor noise: offsets commanded (corrected) and held at 0;
//   4. per-pass errors, final-shape predictions against the truth, offsets, the corrected program,
//      summary.json (loop/closed_loop_report.hpp).
// Stages 1-2 are kept under options.out and reused while the case that made them is unchanged.
#include "loop/closed_loop_report.hpp"
#include "loop/closed_loop_setup.hpp"

#include <nlohmann/json.hpp>

#include <optional>

namespace drom::loop {

struct RunResult {
  Headline headline;
  nlohmann::json summary;  // summary.json's content
  online::LoopSimulationResult corrected, uncorrected;
  int model_rank = 0;
  std::optional<machine::ProgramVerdict> program_verdict;  // the corrected program's, on the [sync] machine
};

RunResult run_closed_loop(const case_file::Case& c, const RunOptions& options);

}  // namespace drom::loop
