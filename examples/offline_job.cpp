// drom example 1: run an offline job for a case.
//
// Sample runs:
//   offline_job --out out/plate_db                     (the embedded flat plate, as written: about 30 min)
//   offline_job --set mesh.nx=10 --set mesh.ny=10 --set path.station_spacing=300 --out out/coarse_db
//   offline_job cases/curved_panel.toml --set mesh.nx=12 --set mesh.ny=12 --out out/panel_db
//
// The job simulates the machining station by station, once per unit stress profile of the case's
// basis, and writes the snapshot database (database.h5) and summary.json into --out. Interrupt it and
// run it again with --resume: it continues where it stopped and writes the same bytes.
#include "case_file/case.hpp"
#include "offline/offline_job.hpp"
#include "support/input_error.hpp"

#include <cstdio>
#include <string>
#include <vector>

int main(int argc, char* argv[]) {
  // 1. Arguments: an optional case file, --set overrides, --out, --resume.
  std::optional<std::filesystem::path> case_file;
  std::vector<std::string> overrides;
  drom::offline::JobOptions options;
  options.out = "out/offline_db";
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--set" && i + 1 < argc) overrides.push_back(argv[++i]);
    else if (a == "--out" && i + 1 < argc) options.out = argv[++i];
    else if (a == "--resume") options.resume = true;
    else case_file = a;
  }
  try {
    // 2. The case: a file, or the embedded flat plate; every key checked, --set applied.
    const drom::case_file::Case c = drom::case_file::load_case(case_file, overrides);

    // 3. Progress through the callback (return false to stop; the job is then resumable).
    options.quiet = true;
    options.progress = [](std::size_t saved, std::size_t total) {
      std::fprintf(stderr, "\r  station %zu/%zu", saved, total);
      return true;
    };

    // 4. The job: removal, equilibrium, then the stations on every core.
    const auto result = drom::offline::run_job(c, drom::offline::JobKind::Offline, options);
    std::fprintf(stderr, "\n");

    // 5. What it wrote.
    if (!result.finished) {
      std::printf("stopped after %zu of %zu stations; run again with --resume\n", result.stations_saved, result.stations);
      return 0;
    }
    std::printf("%s: %zu stations x %d profiles -> %s (%.1f MB, %.1f s)\n", c.name.c_str(), result.stations, result.summary["profiles"].get<int>(),
                (options.out / "database.h5").string().c_str(), result.summary["database_mb"].get<double>(), result.summary["time_s"].get<double>());
    return 0;
  } catch (const drom::InputError& e) {
    std::fprintf(stderr, "offline_job: %s\n", e.what());
    return 2;
  }
}
