// drom example 2: reduce an offline database to the light model the online predictor loads.
//
// Sample runs:
//   reduce_database out/coarse_db/database.h5 --out out/coarse_model/model.h5
//   reduce_database out/panel_db/database.h5 --tol 5e-4 --top-margin 90 --out out/panel_model/model.h5
//
// The POD is truncated by the seed's max-norm bound at --tol (mm); the basis histories are kept in
// separated space-time form. Beside model.h5 come the modes as VTK, the singular values (CSV, PNG) and
// summary.json.
#include "reduce/database_reduction.hpp"
#include "support/input_error.hpp"

#include <cstdio>
#include <string>

int main(int argc, char* argv[]) {
  // 1. Arguments: the database, the tolerance, the stock's top margin, the model file.
  std::filesystem::path database, model_file = "out/model/model.h5";
  drom::reduce::DatabaseReductionSettings settings;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--tol" && i + 1 < argc) settings.tolerance = std::stod(argv[++i]);
    else if (a == "--top-margin" && i + 1 < argc) settings.top_margin = std::stod(argv[++i]);
    else if (a == "--out" && i + 1 < argc) model_file = argv[++i];
    else database = a;
  }
  if (database.empty()) {
    std::fprintf(stderr, "usage: reduce_database DATABASE.h5 [--tol MM] [--top-margin MM] [--out MODEL.h5]\n");
    return 2;
  }
  try {
    // 2. Read the database (its format version is checked) and reduce it.
    const auto reduced = drom::reduce::reduce_database(database, settings);

    // 3. Write the model and its pictures.
    drom::reduce::write_reduction(model_file, reduced);

    // 4. What it kept, and the bound it guarantees against the database.
    const auto& m = reduced.model;
    std::printf("%s: rank %d of %ld profiles, error bound %.3g mm (measured %.3g mm) -> %s\n", reduced.case_name.c_str(), m.rank(), reduced.profiles,
                m.error_bound(), reduced.report.measured_max_error, model_file.string().c_str());
    return 0;
  } catch (const drom::InputError& e) {
    std::fprintf(stderr, "reduce_database: %s\n", e.what());
    return 2;
  }
}
