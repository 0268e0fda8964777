#pragma once
// The closed loop's outputs (docs/outputs.md, "drom run"): per-pass tables, plots, final-shape VTK,
// the offset stream, the corrected program, and the headline figures both drom run and drom study
// report.
#include "case_file/case.hpp"
#include "machine/post_processor.hpp"
#include "machine/program_verdict.hpp"
#include "online/loop_simulation.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>

namespace drom::loop {

struct Headline {
  double learned_at = -1;          // program time (s); -1: never
  int learned_pass = 0;            // the pass during which it learned (0: before any)
  double uncorrected_max = 0;      // mm, over all passes
  double corrected_max_from_3 = 0; // mm, path error from pass 3 on (with correction)
  double corrected_mean_from_3 = 0;
  int shape_pass = 3;              // the pass whose end the final-shape target looks at
  double shape_error_at_pass = 0;  // mm, final-shape max error at the end of shape_pass
  double shape_error_end = 0, shape_rms_end = 0, band_coverage_end = 0;
  nlohmann::json to_json() const;
};

Headline headline(const online::LoopSimulationResult& corrected, const online::LoopSimulationResult& uncorrected, int shape_pass);

struct LoopOutputs {
  std::vector<std::string> files;  // written into `out`
  // The corrected program read back and judged on the case's [sync] machine before it is written
  // (machine/program_verdict.hpp); none without one. A program beyond a stroke is not written.
  std::optional<machine::ProgramVerdict> program_verdict;
};

// The [program] table as the post-processor takes it (the tool's diameter from [tool]).
machine::PostOptions post_options(const case_file::Case& c);

// Writes passes.csv/.png, path_samples.csv, final_shape_error.csv/.png, final_shape_pass_<k>.vtu
// (+ .pvd), offsets.csv and corrected_program.nc into `out`.
LoopOutputs write_loop_outputs(const std::filesystem::path& out, const case_file::Case& c, const reduce::LightModel& model, const online::TruePart& truth,
                               const online::LoopSimulationResult& corrected, const online::LoopSimulationResult& uncorrected);

// The corrected program: the model's path with the commanded offsets written into Z on the floor,
// in the shape every posted program has (machine/post_processor.hpp): the header with the tool and
// the spindle, a retract to the clearance plane (the path's highest point + post.clearance) before
// the first X Y move, a plunge to the path's start at its first feed, and M5 M30 at the end. Cuts
// keep the path's timing; retracts and moves across at the path's top are rapids (G0). Each offset
// step is ramped in over 20 ms, and a plunge onto the floor goes to the corrected depth.
std::string corrected_gcode(const reduce::LightModel& model, const std::vector<online::Pass>& passes, const std::vector<online::OffsetCommand>& offsets,
                            const machine::PostOptions& post);

}  // namespace drom::loop
