#include "offline/station_solvers.hpp"

#include "fem/elastic_problem.hpp"
#include "fem/supports.hpp"
#include "fem/vtk_output.hpp"
#include "offline/station_schedule.hpp"
#include "support/resources.hpp"
#include "pgd/pgd_problem.hpp"

#include <algorithm>
#include <chrono>
#include <stdexcept>

namespace drom::offline {

namespace {

// Best-fit rigid motion removed from each column, over the nodes that material holds.
void remove_rigid_motions(const fem::Mesh& mesh, const std::vector<char>& live, Eigen::MatrixXd& U) {
  std::vector<int> nodes;
  for (std::size_t n = 0; n < live.size(); ++n)
    if (live[n]) nodes.push_back(static_cast<int>(n));
  for (Eigen::Index p = 0; p < U.cols(); ++p) {
    Eigen::VectorXd u = U.col(p);
    fem::remove_rigid_motion(mesh, nodes, u);
    U.col(p) = u;
  }
}

// ---- 3D finite elements -------------------------------------------------------------------------

class FeStation final : public StationSolver {
 public:
  FeStation(const PartModel& part, const std::vector<fem::StressProfile>& profiles, const std::vector<int>& clamped, const fem::ElasticProblem& base,
            double residual_bound)
      : part_(part), profiles_(profiles), base_(base), clamped_(part.mesh, part.shape, part.material, profiles) {
    clamped_.adopt_equilibrium(base);
    clamped_.set_fixed_dofs(clamped);
    clamped_.set_residual_bound(residual_bound);
  }

  void start_chunk(const fem::RunChanges& changes) override {
    changes_ = changes;
    anchor_next_ = true;
  }

  Eigen::MatrixXd solve(const std::vector<double>& activity, bool follows_previous) override {
    clamped_.set_activity(activity);
    if (anchor_next_)
      clamped_.assemble_and_factorize_anchor(changes_);
    else if (follows_previous)
      clamped_.refactorize_changed();
    else
      clamped_.assemble_and_factorize();
    anchor_next_ = false;
    last_ = &clamped_;
    return clamped_.solve();
  }

  Eigen::MatrixXd free_shape(const std::vector<double>& activity) override {
    free_ = std::make_unique<fem::ElasticProblem>(part_.mesh, part_.shape, part_.material, profiles_);
    free_->adopt_equilibrium(base_);
    free_->set_activity(activity);
    const auto live = free_->live_nodes();
    free_->set_fixed_dofs(fem::isostatic_dofs(part_.mesh, part_.shape, live));
    free_->assemble_and_factorize();
    Eigen::MatrixXd U = free_->solve();
    remove_rigid_motions(part_.mesh, live, U);
    for (int d = 0; d < part_.mesh.dof_count(); ++d)
      if (free_->orphan_dofs()[static_cast<std::size_t>(d)]) U.row(d).setZero();
    last_ = free_.get();
    return U;
  }

  void write_vtu(const std::filesystem::path& path, const NamedDisplacements& displacements, std::size_t) const override {
    if (!last_) throw std::logic_error("write_vtu before a solve");
    fem::write_solution_vtu(path, *last_, displacements);
  }

  nlohmann::json statistics() const override {
    const auto& b = clamped_.block_stats();
    nlohmann::json s{{"assembly_s", clamped_.assembly_seconds()},
                     {"analyze_s", clamped_.solver_stats().analyze_seconds},
                     {"factorize_s", clamped_.solver_stats().factorize_seconds},
                     {"factorizations", clamped_.solver_stats().factorizations},
                     {"block", {{"anchors", b.anchors},
                                {"anchors_by_first_change", b.anchors_by_first_change},
                                {"block_dofs", b.block_dofs},
                                {"block_refactorizations", b.block_refactorizations},
                                {"trailing_dofs", b.trailing_dofs},
                                {"unchanged_stations", b.unchanged_stations},
                                {"full_chunks", b.full_chunks},
                                {"residual_fallbacks", b.residual_fallbacks},
                                {"whole_residuals", b.whole_residuals},
                                {"anchor_s", b.anchor_seconds},
                                {"refactorize_s", b.refactorize_seconds},
                                {"solve_s", b.solve_seconds},
                                {"residual_s", b.residual_seconds},
                                {"worst_residual", b.worst_residual}}}};
    if (free_) accumulate(s, {{"factorize_s", free_->solver_stats().factorize_seconds}, {"factorizations", free_->solver_stats().factorizations}});
    return s;
  }

 private:
  const PartModel& part_;
  const std::vector<fem::StressProfile>& profiles_;
  const fem::ElasticProblem& base_;
  fem::ElasticProblem clamped_;
  fem::RunChanges changes_;
  bool anchor_next_ = false;
  std::unique_ptr<fem::ElasticProblem> free_;
  const fem::ElasticProblem* last_ = nullptr;
};

class FeSolvers final : public StationSolvers {
 public:
  FeSolvers(const case_file::Case& c, const PartModel& part, const std::vector<fem::StressProfile>& profiles, const std::vector<int>& clamped,
            const std::vector<int>& groups, std::string_view equilibrium)
      : part_(part),
        profiles_(profiles),
        clamped_(clamped),
        chunk_(static_cast<std::size_t>(std::max(1, c.stations_per_factorization))),
        automatic_(c.stations_per_factorization == 0),
        residual_bound_(c.residual_bound),
        base_(part.mesh, part.shape, part.material, profiles) {
    if (!groups.empty()) base_.set_profile_groups(groups);
    if (!equilibrium.empty())
      base_.adopt_equilibrium(equilibrium);
    else
      base_.equilibrate(fem::isostatic_dofs(part.mesh, part.shape, std::vector<char>(static_cast<std::size_t>(part.mesh.node_count()), 1)));
  }
  std::string equilibrium() const override { return base_.equilibrium_bytes(); }
  std::unique_ptr<StationSolver> make_worker() const override {
    return std::make_unique<FeStation>(part_, profiles_, clamped_, base_, residual_bound_);
  }
  std::size_t chunk() const override { return chunk_; }
  nlohmann::json plan(const ActivityHistory& history) override {
    if (!automatic_) return {{"stations_per_factorization", chunk_}, {"chosen", false}};
    const auto start = std::chrono::steady_clock::now();
    const double flops = base_.full_factorization_flops();
    const auto choice = choose_stations_per_factorization(history, part_.mesh, flops);
    chunk_ = choice.chunk;
    nlohmann::json estimates = nlohmann::json::object();
    for (const auto& [C, cost] : choice.estimates) estimates[std::to_string(C)] = cost / (flops * static_cast<double>(history.stations()));
    return {{"stations_per_factorization", chunk_},
            {"chosen", true},
            {"full_factorization_flops", flops},
            {"estimated_cost_per_station_in_full_factorizations", estimates},
            {"plan_s", seconds_since(start)}};
  }
  nlohmann::json equilibrium_statistics() const override { return {{"factorize_s", base_.solver_stats().factorize_seconds}}; }

 private:
  const PartModel& part_;
  std::vector<fem::StressProfile> profiles_;
  std::vector<int> clamped_;
  std::size_t chunk_;
  bool automatic_;  // solver.stations_per_factorization = "auto": plan() chooses chunk_
  double residual_bound_;
  fem::ElasticProblem base_;
};

// ---- PGD on the plane x thickness tensor grid -----------------------------------------------------

void add_reports(nlohmann::json& s, const std::vector<pgd::PgdReport>& reports) {
  for (const auto& r : reports) {
    nlohmann::json add{{"solves", 1},
                       {"modes", r.modes_added},
                       {"fixed_point_iterations", r.fixed_point_iterations},
                       {"updates", r.updates},
                       {"plane_factorizations", r.plane_factorizations},
                       {"unconverged", r.converged ? 0 : 1},
                       {"solve_s", r.seconds},
                       {"update_s", r.update_seconds}};
    accumulate(s, add);
    s["worst_residual_ratio"] = std::max(s.value("worst_residual_ratio", 0.0), r.final_ratio);
  }
}

class PgdStation final : public StationSolver {
 public:
  PgdStation(const case_file::Case& c, const PartModel& part, const std::vector<fem::StressProfile>& profiles, const std::vector<int>& clamped,
             const pgd::PgdProblem& base)
      : part_(part), problem_(base.grid(), part.material, profiles, pgd_settings(c), c.pgd_penalty, c.pgd_indicator_tolerance) {
    problem_.adopt_equilibrium(base);
    problem_.set_fixed_dofs(clamped);
  }

  Eigen::MatrixXd solve(const std::vector<double>& activity, bool follows_previous) override {
    problem_.set_activity(activity);
    const auto& fields = problem_.solve(follows_previous);
    add_reports(statistics_, problem_.reports());
    return nodal(fields);
  }

  Eigen::MatrixXd free_shape(const std::vector<double>& activity) override {
    problem_.set_activity(activity);
    Eigen::MatrixXd U = nodal(problem_.solve_free());
    add_reports(statistics_, problem_.reports());
    const auto live = problem_.live_nodes();
    remove_rigid_motions(part_.mesh, live, U);
    for (std::size_t n = 0; n < live.size(); ++n)
      if (!live[n]) U.middleRows(3 * static_cast<Eigen::Index>(n), 3).setZero();
    return U;
  }

  void write_vtu(const std::filesystem::path& path, const NamedDisplacements& displacements, std::size_t first_profile) const override {
    fem::VtuFields fields;
    fields.point_vectors = displacements;
    fields.cell_scalars = {{"activity", problem_.activity()}};
    std::vector<char> keep(problem_.activity().size());
    for (std::size_t e = 0; e < keep.size(); ++e) keep[e] = problem_.activity()[e] > 0;
    fem::write_vtu(path, part_.mesh, fields, keep);
    // The separated solution itself beside it: the modes of each profile.
    const auto& solutions = problem_.solutions();
    for (std::size_t p = 0; first_profile + p < solutions.size() && p < displacements.size(); ++p) {
      const std::string suffix = displacements.size() > 1 ? displacements[p].first.substr(std::string("displacement").size()) : "";
      auto modes = path;
      modes.replace_filename(path.stem().string() + "_modes" + suffix + ".h5");
      pgd::write_modes_hdf5(modes, problem_.grid(), solutions[first_profile + p]);
    }
  }

  nlohmann::json statistics() const override { return statistics_; }

 private:
  Eigen::MatrixXd nodal(const std::vector<pgd::SeparatedField>& fields) const {
    Eigen::MatrixXd U(3 * problem_.grid().node_count(), static_cast<Eigen::Index>(fields.size()));
    for (std::size_t p = 0; p < fields.size(); ++p) U.col(static_cast<Eigen::Index>(p)) = fields[p].cartesian_nodal(problem_.grid());
    return U;
  }

  const PartModel& part_;
  pgd::PgdProblem problem_;
  nlohmann::json statistics_ = nlohmann::json::object();
};

class PgdSolvers final : public StationSolvers {
 public:
  PgdSolvers(const case_file::Case& c, const PartModel& part, const std::vector<fem::StressProfile>& profiles, const std::vector<int>& clamped)
      : case_(c),
        part_(part),
        profiles_(profiles),
        clamped_(clamped),
        base_(pgd::TensorGrid::make(part.shape, c.nx, c.ny, c.nz, c.thickness_grading), part.material, profiles, pgd_settings(c), c.pgd_penalty,
              c.pgd_indicator_tolerance) {
    // The PGD numbers its unknowns on its tensor grid; the case's Hex27 mesh must be that grid's.
    const fem::Mesh grid_mesh = base_.grid().hex27_mesh();
    if (grid_mesh.node_count() != part.mesh.node_count() || grid_mesh.connectivity != part.mesh.connectivity)
      throw std::logic_error("PGD: the case's Hex27 mesh is not the tensor grid's");
    base_.equilibrate();
  }
  std::unique_ptr<StationSolver> make_worker() const override { return std::make_unique<PgdStation>(case_, part_, profiles_, clamped_, base_); }
  std::size_t chunk() const override { return 16; }
  std::string equilibrium() const override { return {}; }
  nlohmann::json equilibrium_statistics() const override {
    nlohmann::json s = nlohmann::json::object();
    add_reports(s, base_.equilibration_reports());
    return s;
  }

 private:
  const case_file::Case& case_;
  const PartModel& part_;
  std::vector<fem::StressProfile> profiles_;
  std::vector<int> clamped_;
  pgd::PgdProblem base_;
};

}  // namespace

void accumulate(nlohmann::json& total, const nlohmann::json& add) {
  for (auto it = add.begin(); it != add.end(); ++it) {
    if (it.value().is_object()) {
      if (!total.contains(it.key())) total[it.key()] = nlohmann::json::object();
      accumulate(total[it.key()], it.value());
    } else if (it.key().rfind("worst_", 0) == 0) {
      total[it.key()] = std::max(total.value(it.key(), 0.0), it.value().get<double>());
    } else if (it.value().is_number_integer()) {
      total[it.key()] = total.value(it.key(), 0) + it.value().get<long long>();
    } else if (it.value().is_number()) {
      total[it.key()] = total.value(it.key(), 0.0) + it.value().get<double>();
    }
  }
}

std::unique_ptr<StationSolvers> StationSolvers::create(const case_file::Case& c, const PartModel& part, const std::vector<fem::StressProfile>& profiles,
                                                       const std::vector<int>& clamped, const std::vector<int>& groups, std::string_view equilibrium) {
  // The PGD solves every profile on its own already.
  if (c.solver == "pgd") return std::make_unique<PgdSolvers>(c, part, profiles, clamped);
  return std::make_unique<FeSolvers>(c, part, profiles, clamped, groups, equilibrium);
}

}  // namespace drom::offline
