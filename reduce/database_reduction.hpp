#pragma once
// The reduce stage (docs/design.md §5): an offline snapshot database in, the light model the online
// predictor loads out. The database carries all it needs (the target's and the final part's faces,
// the stock's top, the programmed path with its times, the tool, the case's own coefficients), so this
// stage reads it alone.
//
// Example (examples/reduce_database.cpp):
//   drom::reduce::DatabaseReductionSettings settings;
//   settings.tolerance = 1e-3;
//   const auto reduced = drom::reduce::reduce_database("out/panel_db/database.h5", settings);
//   drom::reduce::write_reduction("out/panel_model/model.h5", reduced);
#include "reduce/light_model.hpp"
#include "reduce/model_reduction.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

namespace drom::reduce {

struct DatabaseReductionSettings {
  double tolerance = 1e-3;          // mm: the POD's max-norm error bound (seed eq. 2.9)
  double history_tolerance = -1;    // mm, the space-time compressions together; < 0: tolerance / 2
  double profile_scale = -1;        // MPa per unit profile; <= 0: the case's largest coefficient (50 without one)
  int max_rank = -1;                // cap on the POD's rank; -1: none
  bool prior_mean_from_case = true; // the prior's mean: the case's [stress] profile (else zero)
  double top_margin = -1;           // mm around the pocket of the stock's top to keep; < 0: none
};

struct DatabaseReduction {
  LightModel model;
  ReductionSettings settings;  // as applied
  ReductionReport report;
  std::filesystem::path database;
  std::string case_name;
  std::size_t target_nodes = 0, target_nodes_never_cut = 0, top_nodes = 0;
  long profiles = 0;
  double last_station_time = 0;
};

// Reads the database (checking its format version) and reduces it. Throws InputError for a database
// that is not an offline one, or malformed.
DatabaseReduction reduce_database(const std::filesystem::path& database, const DatabaseReductionSettings& settings);

// Writes the model file (atomically) and, beside it, target_modes.vtu, final_shape_modes.vtu,
// singular_values.csv and .png, and summary.json. Returns the summary.
nlohmann::json write_reduction(const std::filesystem::path& model_file, const DatabaseReduction& reduction, double seconds = 0);

}  // namespace drom::reduce
