// drom deviation: an unknown blank's deviation learned during the approach (loop/deviation_study.hpp).
#include "apps/commands.hpp"
#include "loop/deviation_study.hpp"
#include "support/input_error.hpp"

#include <cstdio>

namespace drom::app {

int deviation_command(const CommandOptions& options) {
  if (!options.case_path) throw InputError("drom deviation needs a deviation case, e.g. drom deviation cases/deviation.toml");
  const loop::DeviationCase c = loop::load_deviation_case(*options.case_path, options.overrides);
  const auto s = loop::run_deviation_study(c, options.out, options.quiet);
  if (options.quiet) return 0;
  std::printf("drom deviation: %s\n", c.name.c_str());
  std::printf("  basis                  r = %d of %d family members (bound %.2g mm)\n", s["rank"].get<int>(), s["family_members"].get<int>(),
              s["pod_max_bound_mm"].get<double>());
  std::printf("  scan extent needed     %.1f s of program (%.0f mm); cutting starts at %.1f s\n", s["scan_extent_program_time_s"].get<double>(),
              s["scan_extent_path_mm"].get<double>(), s["cutting_starts_s"].get<double>());
  std::printf("  learned at             %.1f s of program\n", s["learned_at_program_time_s"].get<double>());
  std::printf("  path error             %.4f mm corrected, %.4f mm without (tolerance %.3g)\n", s["max_error_corrected_mm"].get<double>(),
              s["max_error_uncorrected_mm"].get<double>(), s["path_tolerance_mm"].get<double>());
  std::printf("  identification error   %.4f mm at learning, %.4f mm at the end (whole area)\n", s["identification_max_error_at_learning_mm"].get<double>(),
              s["identification_max_error_end_mm"].get<double>());
  return 0;
}

}  // namespace drom::app
