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

}  // namespace

nlohmann::json run_layer_check(const cases::Case& c, const std::filesystem::path& out, bool quiet) {
  Steps steps(6, quiet);
  steps.begin("meshing the part");
  const PartModel part = build_part(c);
  const auto clamped = clamp_dofs(c, part);
  const auto& mesh = part.mesh;
  if (!quiet)
    std::cerr << "      " << c.name << ": " << mesh.element_count() << " " << fem::element_name(mesh.type) << " elements, " << mesh.dof_count()
              << " unknowns\n";

  steps.begin("equilibrating the residual stress on the free stock");
  fem::ElasticProblem problem(mesh, part.shape, part.material, {part.profile});
  const std::vector<char> all_nodes(static_cast<std::size_t>(mesh.node_count()), 1);
  problem.equilibrate(fem::isostatic_dofs(mesh, part.shape, all_nodes));

  fem::PvdCollection pvd;
  steps.begin("solving the intact stock, clamped");
  problem.set_fixed_dofs(clamped);
  problem.assemble_and_factorize();
  const Eigen::VectorXd intact = record(out, problem, "0_intact", problem.solve().col(0), pvd);

  steps.begin("thinning the stock by the pocket depth everywhere, clamped");
  const auto criterion = c.removal_criterion == "centroid" ? fem::RemovalCriterion::Centroid : fem::RemovalCriterion::VolumeFraction;
  problem.set_activity(fem::layer_activity(mesh, part.shape, c.pocket_depth, criterion));
  problem.assemble_and_factorize();
  const Eigen::VectorXd thinned = record(out, problem, "1_thinned_clamped", problem.solve().col(0), pvd);

  steps.begin("unclamping the thinned stock (3-2-1 supports, best-fit alignment)");
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
  const Eigen::VectorXd free_shape = record(out, problem, "2_thinned_free", aligned, pvd);

  steps.begin("writing summary.json");
  pvd.write(out / "layer.pvd");

  auto max_vertical = [](const Eigen::VectorXd& u) {
    double m = 0;
    for (Eigen::Index i = 2; i < u.size(); i += 3) m = std::max(m, std::abs(u[i]));
    return m;
  };
  nlohmann::json summary = {
      {"command", "layer"},
      {"stage", "fem core: intact and uniformly thinned stock against the closed form of layer removal"},
      {"case", c.name},
      {"case_origin", c.origin},
      {"mesh", {{"element", fem::element_name(mesh.type)}, {"elements", mesh.element_count()}, {"unknowns", mesh.dof_count()}}},
      {"equilibrium_residual_relative", problem.equilibrium_residual()},
      {"intact_clamped_max_displacement_mm", intact.cwiseAbs().maxCoeff()},
      {"thinned_clamped_max_vertical_displacement_mm", max_vertical(thinned)},
      {"thinned_free_max_vertical_displacement_mm", max_vertical(free_shape)},
      {"timing_s",
       {{"total", steps.elapsed()},
        {"assembly", problem.assembly_seconds()},
        {"analyze", problem.solver_stats().analyze_seconds},
        {"factorize", problem.solver_stats().factorize_seconds},
        {"solve", problem.solver_stats().solve_seconds}}},
      {"cholmod_peak_memory_mb", static_cast<double>(problem.solver_stats().factor_peak_bytes) / 1048576.0},
      {"machine", machine_info()},
      {"files", {"layer.pvd", "layer_0_intact.vtu", "layer_1_thinned_clamped.vtu", "layer_2_thinned_free.vtu"}}};

  if (part.shape.kind() == fem::PartShape::Kind::Plate) {
    // The free thinned plate is the closed-form case: compare curvatures away from the edges.
    const auto centre = fem::nodes_where(mesh, [&](const Eigen::Vector3d& p) {
      return p.z() < 1e-9 && std::abs(p.x() - c.length_x / 2) < 0.2 * c.length_x && std::abs(p.y() - c.length_y / 2) < 0.2 * c.length_y;
    });
    const Eigen::Vector2d fe = fem::fit_plate_curvature(mesh, centre, free_shape);
    const auto exact = fem::layer_removal_closed_form(part.profile, c.thickness, c.pocket_depth, c.young_modulus, c.poisson_ratio);
    const double err = (fe - exact.curvature).cwiseAbs().maxCoeff() / exact.curvature.cwiseAbs().maxCoeff();
    summary["free_plate_curvature_per_mm"] = {{"fe", {fe.x(), fe.y()}}, {"closed_form", {exact.curvature.x(), exact.curvature.y()}}, {"relative_error", err}};
  }
  write_summary(out, summary);
  return summary;
}

}  // namespace drom::offline
