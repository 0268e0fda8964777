#pragma once
// The machining states of drom offline / truth, solved by the case's solver: the 3D FE core
// (solver.kind = "fe") or the plane x thickness PGD (solver.kind = "pgd"). Both equilibrate the stock
// once; each worker thread then gets its own solver of the clamped states.
#include "offline/activity_history.hpp"
#include "offline/part_setup.hpp"

#include <nlohmann/json.hpp>

#include <Eigen/Core>

#include <filesystem>
#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace drom::offline {

using NamedDisplacements = std::vector<std::pair<std::string, Eigen::VectorXd>>;

class StationSolver {
 public:
  virtual ~StationSolver() = default;
  // Displacement of every node (3 * node + Cartesian component), one column per stress profile, of
  // the clamped part with these remaining fractions. `follows_previous`: the last call solved the
  // previous station, so its solution may seed this one.
  virtual Eigen::MatrixXd solve(const std::vector<double>& activity, bool follows_previous) = 0;
  // Before the first station of a chunk: what the chunk's later stations change, and when
  // (ActivityHistory::run_changes). The FE factorizes the first station with their dofs last, and
  // the later ones refactorize only those (fem/trailing_block_cholesky.hpp).
  virtual void start_chunk(const fem::RunChanges& changes) { (void)changes; }
  // The unclamped part's shape with these remaining fractions, after best-fit rigid alignment; dofs of
  // nodes that no material holds are 0.
  virtual Eigen::MatrixXd free_shape(const std::vector<double>& activity) = 0;
  // The state of the last solve (or free_shape) to a .vtu, with these displacement columns, which are
  // profiles first_profile, first_profile + 1, ... (the PGD also writes their modes beside it:
  // <stem>_modes[_<profile>].h5).
  virtual void write_vtu(const std::filesystem::path& path, const NamedDisplacements& displacements, std::size_t first_profile = 0) const = 0;
  // Solver figures for summary.json (seconds, counts); workers' figures are summed.
  virtual nlohmann::json statistics() const = 0;
};

class StationSolvers {
 public:
  virtual ~StationSolvers() = default;
  // Equilibrates the intact stock under each profile. `groups` (sizes, in order; empty: one group):
  // profiles loaded and solved apart, so that each group's columns are bit for bit what a run of that
  // group alone gives (drom run computes the offline and truth databases in one pass).
  // `equilibrium`: what equilibrium() of another process's solvers for the same case gave (rank 0 of
  // an MPI job); adopted instead of equilibrating again when not empty.
  static std::unique_ptr<StationSolvers> create(const case_file::Case& c, const PartModel& part, const std::vector<fem::StressProfile>& profiles,
                                                const std::vector<int>& clamped, const std::vector<int>& groups = {},
                                                std::string_view equilibrium = {});
  virtual std::unique_ptr<StationSolver> make_worker() const = 0;
  // Stations a worker takes at a time and solves in order: the FE factorizes a chunk's first station
  // and refactorizes only what the tool changes at the others (solver.stations_per_factorization,
  // 1: a full factorization per station; "auto": plan()'s choice); the PGD warm-starts each station from the previous one.
  // Chunks start cold, so the results do not depend on the thread count nor on where a run was
  // interrupted.
  virtual std::size_t chunk() const = 0;
  // Before chunk() is asked, on every rank: the job's removal history, from which the FE chooses its
  // stations per factorization when the case says "auto" (offline/station_schedule.hpp). Returns
  // what it chose, for summary.json (empty: nothing to choose).
  virtual nlohmann::json plan(const ActivityHistory& history) { (void)history; return nlohmann::json::object(); }
  virtual nlohmann::json equilibrium_statistics() const = 0;
  // The equilibrated stock as bytes for create(); empty when the solver cannot hand it over (the PGD's
  // separated fields: each rank equilibrates on its own, with the same bytes as a result).
  virtual std::string equilibrium() const = 0;
};

// Sums the numbers of two statistics objects key by key (nested objects too); "worst_*" keys keep the
// larger value.
void accumulate(nlohmann::json& total, const nlohmann::json& add);

}  // namespace drom::offline
