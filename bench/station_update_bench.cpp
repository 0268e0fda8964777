// Issue 28: a case's offline stations solved by full refactorization (what drom did before) and by the
// block refactorization (fem/trailing_block_cholesky.hpp: one factorization per chunk of stations
// with the chunk's machined dofs eliminated last, then only that dense block per station), on the
// same consecutive stations, in the same run, on one thread with single-threaded BLAS (one drom
// offline worker). The case is set up as drom offline does (mesh, clamps, toolpath, removal, unit
// profiles). With --ccx 1, the last of those stations is also exported as a CalculiX deck
// (offline/calculix_export.hpp) and solved by ccx on one thread, in the same run: the ratio of a ccx
// step to a drom station, and how far their answers are apart. Prints JSON.
//   build/bench/station_update_bench CASE.toml [--set key=value]... [--stations 32] [--chunk 16, or 0: chosen as drom offline's "auto"] [--ccx 1]
// e.g. the quick flat plate:
//   build/bench/station_update_bench cases/flat_plate.toml --set mesh.nx=20 --set mesh.ny=20 --set path.station_spacing=100
#include "case_file/case.hpp"
#include "fem/elastic_problem.hpp"
#include "fem/supports.hpp"
#include "offline/calculix_export.hpp"
#include "offline/activity_history.hpp"
#include "offline/machining_run.hpp"
#include "offline/station_schedule.hpp"
#include "offline/part_setup.hpp"
#include "support/kernel_threads.hpp"
#include "support/resources.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <unistd.h>

using namespace drom;

int main(int argc, char** argv) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: station_update_bench CASE.toml [--set key=value]... [--stations N] [--chunk C]\n");
    return 2;
  }
  std::vector<std::string> overrides;
  int wanted = 32, chunk = 16;
  bool calculix = false;
  for (int i = 2; i + 1 < argc; i += 2) {
    if (!std::strcmp(argv[i], "--set")) overrides.emplace_back(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--stations")) wanted = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--chunk")) chunk = std::atoi(argv[i + 1]);
    else if (!std::strcmp(argv[i], "--ccx")) calculix = std::atoi(argv[i + 1]) != 0;
  }
  const SingleThreadedKernels single_threaded_kernels;  // as a drom offline worker
  const case_file::Case c = case_file::load_case(std::string(argv[1]), overrides);
  const offline::PartModel part = offline::build_part(c);
  const auto clamped = offline::clamp_dofs(c, part);
  offline::MachiningRun run(c, part);
  std::vector<std::vector<double>> history;
  offline::ActivityHistory swept(static_cast<std::size_t>(part.mesh.element_count()));
  std::vector<double> remaining(static_cast<std::size_t>(part.mesh.element_count()), 1.0);
  for (std::size_t k = 0; k < run.stations().size() && static_cast<int>(k) < wanted; ++k) {
    run.advance(remaining);
    history.push_back(remaining);
    swept.append(remaining);
  }

  const auto profiles = fem::unit_profiles(part.degrees);
  fem::ElasticProblem full(part.mesh, part.shape, part.material, profiles), block(part.mesh, part.shape, part.material, profiles);
  full.equilibrate(fem::isostatic_dofs(part.mesh, part.shape, std::vector<char>(static_cast<std::size_t>(part.mesh.node_count()), 1)));
  // One ordering for both, as drom offline's workers share the plan's (and the full path's symbolic
  // analysis, once per worker, is outside the stations too).
  const double flops = full.full_factorization_flops();
  block.adopt_equilibrium(full);
  full.set_fixed_dofs(clamped);
  block.set_fixed_dofs(clamped);
  block.set_residual_bound(c.residual_bound);
  full.measure_full_residuals(true);
  // --chunk 0: what drom offline chooses for these stations (solver.stations_per_factorization = "auto").
  std::string estimates;
  if (chunk == 0) {
    const auto choice = offline::choose_stations_per_factorization(swept, part.mesh, flops);
    chunk = static_cast<int>(choice.chunk);
    for (const auto& [C, cost] : choice.estimates) {
      char entry[64];
      std::snprintf(entry, sizeof entry, "%s\"%zu\": %.3f", estimates.empty() ? "" : ", ", C, cost / flops / static_cast<double>(history.size()));
      estimates += entry;
    }
  }

  // The database's rows: the z displacement of the top face's nodes (drom offline's B1_top).
  std::vector<Eigen::Index> top;
  for (int node = 0; node < part.mesh.node_count(); ++node)
    if (part.shape.to_parametric(part.mesh.nodes[static_cast<std::size_t>(node)]).z() > part.shape.thickness() - 1e-9) top.push_back(3 * node + 2);
  const auto P = static_cast<Eigen::Index>(profiles.size());
  Eigen::VectorXd database_max = Eigen::VectorXd::Zero(P), database_diff = database_max;
  double full_s = 0, block_s = 0, worst_refactorized = 0, worst_anchor = 0;
  for (std::size_t k = 0; k < history.size(); ++k) {
    auto t = std::chrono::steady_clock::now();
    full.set_activity(history[k]);
    full.assemble_and_factorize();
    const Eigen::MatrixXd U = full.solve();
    full_s += seconds_since(t);

    const bool anchor = k % static_cast<std::size_t>(chunk) == 0;
    t = std::chrono::steady_clock::now();
    block.set_activity(history[k]);
    if (anchor) {
      // What the chunk's later stations change, and until when.
      block.assemble_and_factorize_anchor(
          swept.run_changes(k, std::min(history.size(), k + static_cast<std::size_t>(chunk)), fem::ElasticProblem::kMinVolumeFraction));
    } else {
      block.refactorize_changed();
    }
    const Eigen::MatrixXd X = block.solve();
    block_s += seconds_since(t);

    for (Eigen::Index p = 0; p < P; ++p) {
      double& worst = anchor ? worst_anchor : worst_refactorized;
      worst = std::max(worst, (X.col(p) - U.col(p)).cwiseAbs().maxCoeff() / U.col(p).cwiseAbs().maxCoeff());
      for (Eigen::Index row : top) {
        database_max(p) = std::max(database_max(p), std::abs(U(row, p)));
        database_diff(p) = std::max(database_diff(p), std::abs(X(row, p) - U(row, p)));
      }
    }
  }
  // The full path's residuals are measured for comparison only, and its one symbolic analysis is
  // done once a job, as the block path's ordering is (before the loop): neither is part of its
  // stations' time.
  full_s -= full.block_stats().residual_seconds + full.solver_stats().analyze_seconds;
  const auto& b = block.block_stats();
  const double ns = static_cast<double>(history.size());
  std::printf("{\n  \"case\": \"%s\",\n  \"unknowns\": %d,\n  \"stations\": %zu,\n  \"chunk\": %d,\n  \"profiles\": %lld,\n", c.name.c_str(), part.mesh.dof_count(),
              history.size(), chunk, static_cast<long long>(P));
  if (!estimates.empty()) std::printf("  \"chunk_chosen_from\": {%s},\n", estimates.c_str());
  std::printf("  \"full_s_per_station\": %.4f,\n  \"block_s_per_station\": %.4f,\n  \"speedup\": %.2f,\n", full_s / ns, block_s / ns, full_s / block_s);
  std::printf("  \"block\": {\"anchors\": %d, \"by_first_change\": %d, \"mean_block_dofs\": %.0f, \"refactorizations\": %d, \"mean_trailing_dofs\": %.0f, \"unchanged_stations\": %d, \"full_chunks\": %d, \"residual_fallbacks\": %d,\n",
              b.anchors, b.anchors_by_first_change, static_cast<double>(b.block_dofs) / std::max(1, b.anchors), b.block_refactorizations,
              static_cast<double>(b.trailing_dofs) / std::max(1, b.block_refactorizations), b.unchanged_stations, b.full_chunks, b.residual_fallbacks);
  std::printf("            \"anchor_s\": %.3f, \"refactorize_s\": %.3f, \"solve_s\": %.3f, \"residual_s\": %.3f},\n", b.anchor_seconds, b.refactorize_seconds,
              b.solve_seconds, b.residual_seconds);
  std::printf("  \"worst_residual\": {\"block\": %.2e, \"full\": %.2e},\n", b.worst_residual, full.block_stats().worst_full_residual);
  std::printf("  \"full_factor_flops\": %.3g,\n", full.solver_stats().factor_flops);
  std::printf("  \"full_factorize_s\": %.3f,\n", full.solver_stats().factorize_seconds);
  // Per profile, relative to its largest value: at the chunks' first stations the block path is a
  // full factorization in another elimination order, which sets the round-off floor.
  std::printf("  \"max_relative_difference\": {\"refactorized_stations\": %.2e, \"anchor_stations\": %.2e, \"database_top_z\": %.2e},\n",
              worst_refactorized, worst_anchor, database_diff.cwiseQuotient(database_max).maxCoeff());
  if (calculix) {
    // One profile (the case's [stress]) against drom's P unit profiles a station: the ratio favours ccx.
    const auto folder = std::filesystem::temp_directory_path() / ("drom_ccx_bench_" + std::to_string(::getpid()));
    const std::size_t station = history.size() - 1;
    const auto exported = offline::export_calculix_station(c, offline::JobKind::Offline, station, folder);
    const auto ccx = fem::run_calculix(exported.deck, exported.deck_stats.nodes, 1);
    const double difference = (ccx.displacement - exported.drom_displacement).cwiseAbs().maxCoeff() / exported.drom_displacement.cwiseAbs().maxCoeff();
    std::printf("  \"calculix\": {\"station\": %zu, \"removed_elements\": %d, \"partial_elements\": %d, \"deck_mb\": %.1f, \"ccx_wall_s\": %.3f, \"ccx_reported_s\": %.3f,\n",
                station, exported.deck_stats.removed, exported.deck_stats.partial, exported.deck_stats.megabytes, ccx.wall_seconds, ccx.reported_seconds);
    std::printf("               \"ccx_over_full_station\": %.1f, \"ccx_over_block_station\": %.1f, \"max_relative_difference\": %.2e},\n",
                ccx.wall_seconds / (full_s / ns), ccx.wall_seconds / (block_s / ns), difference);
    std::filesystem::remove_all(folder);
  }
  std::printf("  \"peak_memory_mb\": %.0f\n}\n", static_cast<double>(peak_memory_bytes()) / 1048576.0);
  return 0;
}
