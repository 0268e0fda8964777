// PGD against 3D FE on the same tensor discretization (Quad9 x Line3 = Hex27), both in one run, on the
// same input: a 1000 x 1000 x 10 flat plate held on four bottom corner pads, a 600 x 600 x 2 pocket
// machined to half its passes (flat floor, so the exact two-term indicator), the default case's even
// profile. For each N_z: wall time, memory (CHOLMOD's factor peak against PGD's stored values) and the
// PGD's max displacement difference to FE, relative. Prints JSON.
//   build/bench/pgd_bench [plane_elements=20] [nz list, default 5,10,20,40,80] [fe_max_nz=40] [anderson_depth=3]
//                         [max_fixed_point_iterations=20] [max_update_functions=45]
//                         [max_modes=80] [update_every=3] [residual_tolerance=1e-3]
//                         [increment_tolerance=1e-3] [update_threads=1] [profiles=1]
// profiles = 6: the offline job's six unit profiles (degrees 2, 4, 6 along and across rolling, 60 MPa
// each) instead of the case's one, as a station of `drom offline` solves them: PGD one greedy solve
// each, FE one factorization and six solves. Also prints the span of the six PGD solutions' thickness
// functions: the size a basis shared by the six would need.
// (defaults: pgd::PgdSettings). Both solvers report their factorizations' floating-point work (CHOLMOD's count):
// flop_ratio = FE's / PGD's, the speed-up at equal flop rates. DROM_PGD_TRACE=1 prints each mode's iterations, residual and energy.
#include "fem/elastic_problem.hpp"
#include "fem/node_sets.hpp"
#include "fem/supports.hpp"
#include "pgd/pgd_problem.hpp"
#include "support/kernel_threads.hpp"
#include "support/resources.hpp"

#include <Eigen/SVD>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <optional>
#include <sstream>
#include <string>

using namespace drom;

int main(int argc, char** argv) {
  const int n = argc > 1 ? std::atoi(argv[1]) : 20;
  std::vector<int> nzs{5, 10, 20, 40, 80};
  if (argc > 2) {
    nzs.clear();
    std::stringstream ss(argv[2]);
    for (std::string item; std::getline(ss, item, ',');) nzs.push_back(std::stoi(item));
  }
  const int fe_max_nz = argc > 3 ? std::atoi(argv[3]) : 40;
  pgd::PgdSettings settings;
  if (argc > 4) settings.anderson_depth = std::atoi(argv[4]);
  if (argc > 5) settings.max_fixed_point_iterations = std::atoi(argv[5]);
  if (argc > 6) settings.max_update_functions = std::atoi(argv[6]);
  if (argc > 7) settings.max_modes = std::atoi(argv[7]);
  if (argc > 8) settings.update_every = std::atoi(argv[8]);
  if (argc > 9) settings.residual_tolerance = std::atof(argv[9]);
  if (argc > 10) settings.increment_tolerance = std::atof(argv[10]);
  if (argc > 11) settings.update_threads = std::atoi(argv[11]);
  const bool unit_profiles = argc > 12 && std::atoi(argv[12]) == 6;
  const fem::Material material{71700.0, 0.33};
  std::vector<fem::StressProfile> profiles{{{2, 4, 6}, {-60, 30, -15}, {-40, 20, -10}}};
  if (unit_profiles) {
    profiles.clear();
    for (std::size_t j = 0; j < 6; ++j) {
      fem::StressProfile unit{{2, 4, 6}, {0, 0, 0}, {0, 0, 0}};
      (j < 3 ? unit.sigma11 : unit.sigma22)[j % 3] = 60;
      profiles.push_back(unit);
    }
  }
  std::printf("{\n  \"plane_elements\": [%d, %d],\n  \"anderson_depth\": %d,\n  \"max_fixed_point_iterations\": %d,\n  \"residual_tolerance\": %g,\n"
              "  \"increment_tolerance\": %g,\n  \"update_every\": %d,\n  \"update_threads\": %d,\n  \"profiles\": %zu,\n  \"runs\": [\n", n, n,
              settings.anderson_depth, settings.max_fixed_point_iterations, settings.residual_tolerance, settings.increment_tolerance,
              settings.update_every, settings.update_threads, profiles.size());
  for (std::size_t r = 0; r < nzs.size(); ++r) {
    const int nz = nzs[r];
    const auto grid = pgd::TensorGrid::make(fem::PartShape::plate(1000, 1000, 10), n, n, nz);
    const fem::Mesh mesh = grid.hex27_mesh();
    // Pocket [200, 800]^2, 2 mm deep, machined over y < 500: half of the passes.
    Eigen::VectorXd plane(grid.plane_elements());
    for (int e = 0; e < grid.plane_elements(); ++e) {
      const double u0 = (e % n) * grid.element_size_u(), v0 = (e / n) * grid.element_size_v();
      const double fu = std::clamp((std::min(800.0, u0 + grid.element_size_u()) - std::max(200.0, u0)) / grid.element_size_u(), 0.0, 1.0);
      const double fv = std::clamp((std::min(500.0, v0 + grid.element_size_v()) - std::max(200.0, v0)) / grid.element_size_v(), 0.0, 1.0);
      plane[e] = fu * fv;
    }
    const auto indicator = pgd::MaterialIndicator::flat_bottom(grid, plane, 8.0);
    std::vector<double> activity(static_cast<std::size_t>(grid.plane_elements() * grid.nt));
    for (int k = 0; k < grid.nt; ++k)
      for (int e = 0; e < grid.plane_elements(); ++e) activity[static_cast<std::size_t>(grid.element(e, k))] = indicator.value(e, k);
    const auto faces = fem::boundary_faces(mesh);
    const auto pads = fem::node_dofs(fem::face_nodes_where(mesh, faces, [&](const Eigen::Vector3d& x) {
      return x.z() < 1e-9 && (x.x() <= 50 || x.x() >= 950) && (x.y() <= 50 || x.y() >= 950);
    }));

    // PGD's 2D solves are small: threads inside them only cost (support/kernel_threads.hpp). FE's 3D
    // factorization keeps its threaded BLAS: each solver runs as it runs best on this machine.
    std::optional<SingleThreadedKernels> single_threaded(std::in_place);
    auto t0 = std::chrono::steady_clock::now();
    pgd::PgdProblem pgd(grid, material, profiles, settings, 1e8, 1e-12);
    pgd.equilibrate();
    const double pgd_equilibrate = seconds_since(t0);
    t0 = std::chrono::steady_clock::now();
    pgd.set_indicator(indicator);
    pgd.set_fixed_dofs(pads);
    pgd.solve(false);
    const double pgd_solve = seconds_since(t0);
    Eigen::MatrixXd u_pgd(3 * grid.node_count(), static_cast<Eigen::Index>(profiles.size()));
    for (std::size_t j = 0; j < profiles.size(); ++j) u_pgd.col(static_cast<Eigen::Index>(j)) = pgd.solutions()[j].cartesian_nodal(grid);
    // Over the profiles: the first's convergence history, the sums of the work.
    pgd::PgdReport rep = pgd.reports().front();
    for (std::size_t j = 1; j < profiles.size(); ++j) {
      const auto& o = pgd.reports()[j];
      rep.modes_added += o.modes_added, rep.fixed_point_iterations += o.fixed_point_iterations, rep.final_ratio = std::max(rep.final_ratio, o.final_ratio);
      rep.plane_solve_seconds += o.plane_solve_seconds, rep.plane_factorizations += o.plane_factorizations, rep.updates += o.updates;
      rep.update_seconds += o.update_seconds, rep.factor_flops += o.factor_flops, rep.update_factor_flops += o.update_factor_flops;
    }
    std::size_t stored = 0;
    for (const auto& f : pgd.solutions()) stored += f.stored_values();
    if (std::getenv("DROM_PGD_TRACE"))
      for (std::size_t q = 0; q < rep.residual_ratio.size(); ++q) std::fprintf(stderr, "mode %zu: %d iterations, ratio %.3e, energy %.3e\n", q + 1, rep.mode_iterations[q], rep.residual_ratio[q], rep.energy_decrease[q]);

    std::printf("    {\"nz\": %d, \"unknowns_3d\": %d, \"pgd\": {\"equilibrate_s\": %.3f, \"solve_s\": %.3f, \"modes\": %d, \"fixed_point_iterations\": %d, "
                "\"residual_ratio\": %.2e, \"stored_values\": %zu, \"plane_solve_s\": %.3f, \"factorizations\": %d, \"updates\": %d, \"update_s\": %.3f, \"factor_gflop\": %.1f, \"update_factor_gflop\": %.1f}",
                nz, 3 * grid.node_count(), pgd_equilibrate, pgd_solve, rep.modes_added, rep.fixed_point_iterations, rep.final_ratio,
                stored, rep.plane_solve_seconds, rep.plane_factorizations, rep.updates, rep.update_seconds, rep.factor_flops / 1e9, rep.update_factor_flops / 1e9);
    if (profiles.size() > 1) {
      // The span of all the solutions' thickness functions, per component: the F of an update
      // shared by the profiles (against each profile's own, which the modes above add up).
      std::printf(", \"shared_basis_functions\": {");
      for (const double tol : {1e-10, 1e-6}) {
        int shared = 0;
        for (std::size_t i = 0; i < 3; ++i) {
          Eigen::MatrixXd stacked(grid.thickness_nodes(), 0);
          for (pgd::SeparatedField f : pgd.solutions()) {
            f.compress(settings.compression_tolerance);  // orthonormal Z, as the update takes them
            stacked.conservativeResize(Eigen::NoChange, stacked.cols() + f.Z[i].cols());
            stacked.rightCols(f.Z[i].cols()) = f.Z[i];
          }
          const Eigen::VectorXd sv = Eigen::JacobiSVD<Eigen::MatrixXd>(stacked).singularValues();
          shared += static_cast<int>((sv.array() > tol * sv[0]).count());
        }
        std::printf("%s\"%g\": %d", tol == 1e-10 ? "" : ", ", tol, shared);
      }
      std::printf("}");
    }
    single_threaded.reset();
    if (nz <= fe_max_nz) {
      t0 = std::chrono::steady_clock::now();
      fem::ElasticProblem fe(mesh, grid.shape, material, profiles);
      fe.equilibrate(fem::isostatic_dofs(mesh, grid.shape, std::vector<char>(static_cast<std::size_t>(mesh.node_count()), 1)));
      const double fe_equilibrate = seconds_since(t0);
      t0 = std::chrono::steady_clock::now();
      fe.set_activity(activity);
      fe.set_fixed_dofs(pads);
      fe.assemble_and_factorize();
      const Eigen::MatrixXd u_fe = fe.solve();
      const double fe_solve = seconds_since(t0);
      // The worst profile's max difference, relative to its own largest FE displacement.
      double relative = 0, max_fe = 0;
      const auto live = fe.live_nodes();
      for (Eigen::Index j = 0; j < u_fe.cols(); ++j) {
        double largest = 0, diff = 0;
        for (int node = 0; node < mesh.node_count(); ++node) {
          if (!live[static_cast<std::size_t>(node)]) continue;
          largest = std::max(largest, u_fe.col(j).segment<3>(3 * node).cwiseAbs().maxCoeff());
          diff = std::max(diff, (u_fe.col(j).segment<3>(3 * node) - u_pgd.col(j).segment<3>(3 * node)).cwiseAbs().maxCoeff());
        }
        relative = std::max(relative, diff / largest);
        max_fe = std::max(max_fe, largest);
      }
      std::printf(", \"fe\": {\"equilibrate_s\": %.3f, \"solve_s\": %.3f, \"factor_gflop\": %.1f, \"factor_peak_mb\": %.1f}, \"max_abs_u_fe_mm\": %.4e, "
                  "\"relative_difference\": %.2e, \"speedup_solve\": %.1f, \"flop_ratio\": %.1f",
                  fe_equilibrate, fe_solve, fe.solver_stats().factor_flops / 1e9, static_cast<double>(fe.solver_stats().factor_peak_bytes) / 1048576.0, max_fe, relative, fe_solve / pgd_solve, fe.solver_stats().factor_flops / std::max(1.0, rep.factor_flops));
    }
    std::printf(", \"peak_rss_mb\": %.0f}%s\n", static_cast<double>(peak_memory_bytes()) / 1048576.0, r + 1 < nzs.size() ? "," : "");
    std::fflush(stdout);
  }
  std::printf("  ]\n}\n");
  return 0;
}
