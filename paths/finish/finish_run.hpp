#pragma once
// `drom finish CASE`: the surface described (PCA, the ball-or-torus verdict), zoned (optimised over K
// with the seed's black box, or one partition as the case asks), finished by parallel planes, timed,
// checked for its scallop, and written out (finish_outputs.hpp, summary.json, the optimisation
// history). The run owns its folder (support/run_folder.hpp): it writes into <out>.partial and swaps
// it in at the end. Each K's optimisation is kept under optimization/, so `--resume` (resume) takes
// up a killed run where it stopped, or reuses the last complete run's finished K values.
#include "paths/finish/finish_case.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>

namespace drom::paths {

struct FinishRunOptions {
  std::filesystem::path out = "out";
  bool quiet = false;
  int threads = 0;  // 0: one per hardware thread (K values run in parallel)
  bool resume = false;
};

nlohmann::json run_finish(const FinishCase& c, const FinishRunOptions& options);

}  // namespace drom::paths
