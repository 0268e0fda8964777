// drom layer: the FE core on its closed-form case (issue 2): equilibrate the case's
// residual stress, solve the intact clamped stock, then the stock thinned by the pocket depth
// everywhere, clamped and then free, and compare the free plate with the closed form.
#include "offline/part_setup.hpp"
#include "support/summary.hpp"
#include "fem/elastic_problem.hpp"
#include "fem/layer_removal.hpp"
#include "fem/node_sets.hpp"
#include "fem/supports.hpp"
#include "fem/vtk_output.hpp"
#include "support/resources.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>

namespace drom::offline {

namespace {

class Steps {
 public:
  Steps(int total, bool quiet) : total_(total), quiet_(quiet), start_(std::chrono::steady_clock::now()) {}
  void begin(const std::string& what) {
    if (!quiet_) std::cerr << "[" << ++done_ << "/" << total_ << " " << elapsed() << " s] " << what << "\n";
  }
  double elapsed() const {
    return std::round(seconds_since(start_) * 10) / 10;
  }

 private:
  int total_, done_ = 0;
  bool quiet_;
  std::chrono::steady_clock::time_point start_;
};

// Writes the problem's state right after its solve (the activity must be that state's).
Eigen::VectorXd record(const std::filesystem::path& out, const fem::ElasticProblem& problem, const std::string& name, Eigen::VectorXd u,
                       fem::PvdCollection& pvd) {
  const std::string file = "layer_" + name + ".vtu";
  fem::write_solution_vtu(out / file, problem, {{"displacement", u}});
  pvd.add(static_cast<double>(pvd.size()), file);
  return u;
}

void describe_mesh(const case_file::Case& c, const fem::Mesh& mesh, bool quiet) {
  if (!quiet)
    std::cerr << "      " << c.name << ": " << mesh.element_count() << " " << fem::element_name(mesh.type) << " elements, " << mesh.dof_count()
              << " unknowns\n";
}

void equilibrate_on_free_stock(fem::ElasticProblem& problem, const PartModel& part) {
  const std::vector<char> all_nodes(static_cast<std::size_t>(part.mesh.node_count()), 1);
  problem.equilibrate(fem::isostatic_dofs(part.mesh, part.shape, all_nodes));
}

Eigen::VectorXd solve_intact_clamped(const std::filesystem::path& out, fem::ElasticProblem& problem, const std::vector<int>& clamped,
                                     fem::PvdCollection& pvd) {
  problem.set_fixed_dofs(clamped);
  problem.assemble_and_factorize();
  return record(out, problem, "0_intact", problem.solve().col(0), pvd);
}

Eigen::VectorXd solve_thinned_clamped(const case_file::Case& c, const PartModel& part, const std::filesystem::path& out, fem::ElasticProblem& problem,
                                      fem::PvdCollection& pvd) {
  const auto criterion = c.removal_criterion == "centroid" ? fem::RemovalCriterion::Centroid : fem::RemovalCriterion::VolumeFraction;
  problem.set_activity(fem::layer_activity(part.mesh, part.shape, c.pocket_depth, criterion));
  problem.assemble_and_factorize();
  return record(out, problem, "1_thinned_clamped", problem.solve().col(0), pvd);
}

// On 3-2-1 supports, after best-fit alignment; the dofs no material holds are 0.
Eigen::VectorXd solve_thinned_free(const PartModel& part, const std::filesystem::path& out, fem::ElasticProblem& problem, fem::PvdCollection& pvd) {
  const auto& mesh = part.mesh;
  const auto live_nodes = problem.live_nodes();
  problem.set_fixed_dofs(fem::isostatic_dofs(mesh, part.shape, live_nodes));
  problem.assemble_and_factorize();
  Eigen::VectorXd aligned = problem.solve().col(0);
  std::vector<int> live_list;
  for (int n = 0; n < mesh.node_count(); ++n)
    if (live_nodes[static_cast<std::size_t>(n)]) live_list.push_back(n);
  fem::remove_rigid_motion(mesh, live_list, aligned);
  for (int d = 0; d < mesh.dof_count(); ++d)
    if (problem.orphan_dofs()[static_cast<std::size_t>(d)]) aligned[d] = 0;
  return record(out, problem, "2_thinned_free", aligned, pvd);
}

// The three states the check solves, in order.
struct LayerStates {
  const Eigen::VectorXd& intact;
  const Eigen::VectorXd& thinned;
  const Eigen::VectorXd& free_shape;
};

nlohmann::json layer_summary(const case_file::Case& c, const fem::Mesh& mesh, const fem::ElasticProblem& problem, const LayerStates& states,
                             const Steps& steps) {
  auto max_vertical = [](const Eigen::VectorXd& u) {
    double m = 0;
    for (Eigen::Index i = 2; i < u.size(); i += 3) m = std::max(m, std::abs(u[i]));
    return m;
  };
  return {
      {"command", "layer"},
      {"stage", "fem core: intact and uniformly thinned stock against the closed form of layer removal"},
      {"case", c.name},
      {"case_origin", c.origin},
      {"mesh", {{"element", fem::element_name(mesh.type)}, {"elements", mesh.element_count()}, {"unknowns", mesh.dof_count()}}},
      {"equilibrium_residual_relative", problem.equilibrium_residual()},
      {"intact_clamped_max_displacement_mm", states.intact.cwiseAbs().maxCoeff()},
      {"thinned_clamped_max_vertical_displacement_mm", max_vertical(states.thinned)},
      {"thinned_free_max_vertical_displacement_mm", max_vertical(states.free_shape)},
      {"timing_s",
       {{"total", steps.elapsed()},
        {"assembly", problem.assembly_seconds()},
        {"analyze", problem.solver_stats().analyze_seconds},
        {"factorize", problem.solver_stats().factorize_seconds},
        {"solve", problem.solver_stats().solve_seconds}}},
      {"cholmod_peak_memory_mb", static_cast<double>(problem.solver_stats().factor_peak_bytes) / 1048576.0},
      {"machine", machine_info()},
      {"files", {"layer.pvd", "layer_0_intact.vtu", "layer_1_thinned_clamped.vtu", "layer_2_thinned_free.vtu"}}};
}

// The free thinned plate is the closed-form case: compare curvatures away from the edges.
nlohmann::json plate_curvature_against_closed_form(const case_file::Case& c, const PartModel& part, const Eigen::VectorXd& free_shape) {
  const auto& mesh = part.mesh;
  const auto centre = fem::nodes_where(mesh, [&](const Eigen::Vector3d& p) {
    return p.z() < 1e-9 && std::abs(p.x() - c.length_x / 2) < 0.2 * c.length_x && std::abs(p.y() - c.length_y / 2) < 0.2 * c.length_y;
  });
  const Eigen::Vector2d fe = fem::fit_plate_curvature(mesh, centre, free_shape);
  const auto exact = fem::layer_removal_closed_form(part.profile, c.thickness, c.pocket_depth, c.young_modulus, c.poisson_ratio);
  const double err = (fe - exact.curvature).cwiseAbs().maxCoeff() / exact.curvature.cwiseAbs().maxCoeff();
  return {{"fe", {fe.x(), fe.y()}}, {"closed_form", {exact.curvature.x(), exact.curvature.y()}}, {"relative_error", err}};
}

}  // namespace

nlohmann::json run_layer_check(const case_file::Case& c, const std::filesystem::path& out, bool quiet) {
  clear_earlier_run(out, "layer");
  Steps steps(6, quiet);
  steps.begin("meshing the part");
  const PartModel part = build_part(c);
  const auto clamped = clamp_dofs(c, part);
  describe_mesh(c, part.mesh, quiet);

  steps.begin("equilibrating the residual stress on the free stock");
  fem::ElasticProblem problem(part.mesh, part.shape, part.material, {part.profile});
  equilibrate_on_free_stock(problem, part);

  fem::PvdCollection pvd;
  steps.begin("solving the intact stock, clamped");
  const Eigen::VectorXd intact = solve_intact_clamped(out, problem, clamped, pvd);
  steps.begin("thinning the stock by the pocket depth everywhere, clamped");
  const Eigen::VectorXd thinned = solve_thinned_clamped(c, part, out, problem, pvd);
  steps.begin("unclamping the thinned stock (3-2-1 supports, best-fit alignment)");
  const Eigen::VectorXd free_shape = solve_thinned_free(part, out, problem, pvd);

  steps.begin("writing summary.json");
  pvd.write(out / "layer.pvd");
  nlohmann::json summary = layer_summary(c, part.mesh, problem, {.intact = intact, .thinned = thinned, .free_shape = free_shape}, steps);
  if (part.shape.kind() == fem::PartShape::Kind::Plate)
    summary["free_plate_curvature_per_mm"] = plate_curvature_against_closed_form(c, part, free_shape);
  write_summary(out, summary);
  return summary;
}

}  // namespace drom::offline
