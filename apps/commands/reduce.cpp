// drom reduce: an offline database to the light model (reduce/database_reduction.hpp).
#include "apps/commands.hpp"
#include "reduce/database_reduction.hpp"
#include "support/input_error.hpp"
#include "support/resources.hpp"

#include <chrono>
#include <cstdio>

namespace drom::app {

int reduce_command(const CommandOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (!options.case_path) throw InputError("drom reduce needs a database: drom reduce OUT/database.h5 --tol MM --out MODEL.h5");
  const std::filesystem::path database = *options.case_path;
  const std::filesystem::path model_file = options.out.extension() == ".h5" ? options.out : options.out / "model.h5";
  reduce::DatabaseReductionSettings settings;
  settings.tolerance = options.tolerance;
  settings.history_tolerance = options.history_tolerance;
  settings.profile_scale = options.profile_scale;
  settings.max_rank = options.max_rank;
  settings.prior_mean_from_case = options.prior_mean == "case";
  settings.top_margin = options.top_margin;
  const auto reduced = reduce::reduce_database(database, settings);
  const auto s = reduce::write_reduction(model_file, reduced, seconds_since(start));
  if (options.quiet) return 0;
  const auto& model = reduced.model;
  std::printf("drom reduce: %s -> %s\n", database.string().c_str(), model_file.string().c_str());
  std::printf("  rank r            %d of %ld profiles (profile scale %.0f MPa)\n", model.rank(), reduced.profiles, reduced.settings.profile_scale);
  std::printf("  error bound       %.3g mm (POD %.3g + histories %.3g; tolerance %.3g + %.3g)\n", model.error_bound(), model.pod_max_bound, model.history_bound,
              reduced.settings.tolerance, reduced.settings.history_tolerance);
  std::printf("  measured max err  %.3g mm against the database\n", reduced.report.measured_max_error);
  if (model.has_top()) std::printf("  stock's top       %zu nodes, measured max err %.3g mm where still there\n", reduced.top_nodes, model.top_error_bound);
  std::printf("  size              %.2f MB (database %.1f MB)\n", s["model_mb"].get<double>(), s["database_mb"].get<double>());
  return 0;
}

}  // namespace drom::app
