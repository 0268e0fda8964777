// Cost of one tool station of the offline job, and what reusing CHOLMOD's symbolic analysis saves:
// on the same stations' matrices, in the same run, (a) a fresh analysis + factorization per
// station against (b) numeric refactorization on the analysis done once (what drom offline does).
// Default flat-plate case mesh (Hex20 40 x 40 x 5, 114 513 unknowns), its toolpath and stations,
// 6 unit profiles. Prints JSON.
//   build/bench/station_bench [stations=8] [nx=40]
#include "fem/elastic_problem.hpp"
#include "fem/mesh_geometry.hpp"
#include "fem/node_sets.hpp"
#include "fem/structured_mesh.hpp"
#include "fem/supports.hpp"
#include "levelset/material_removal.hpp"
#include "levelset/pocket_toolpath.hpp"
#include "support/kernel_threads.hpp"
#include "support/resources.hpp"

#include <chrono>
#include <cstdio>
#include <cstdlib>

using namespace drom;

int main(int argc, char** argv) {
  const int wanted = argc > 1 ? std::atoi(argv[1]) : 8;
  const int n = argc > 2 ? std::atoi(argv[2]) : 40;
  const SingleThreadedKernels single_threaded_kernels;  // as in drom offline

  const geometry::PartShape plate = geometry::PartShape::plate(1000, 1000, 10);
  const fem::Mesh mesh = fem::make_structured_hex_mesh(plate, {n, n, 5, 1.0});
  const paths::ToolAssembly tool = paths::ToolAssembly::flat(12.5, 30);
  const auto path = levelset::pocket_toolpath(plate, {200, 200, 600, 600, 2}, tool, {levelset::PocketStrategy::OneWay, 20, 10, 2, 5, 0.01});
  const levelset::PathTimeline timeline(path);
  const auto stations = levelset::stations_by_spacing(path, timeline, 25);
  levelset::MaterialRemoval removal(levelset::Workpiece::from_shape(plate), tool, 0.5);
  const fem::MeshGeometry elements(mesh);

  const auto degrees = fem::legendre_degrees(fem::ProfileParity::Even, 6);
  fem::ElasticProblem problem(mesh, plate, {71700, 0.33}, fem::unit_profiles(degrees));
  problem.equilibrate(fem::isostatic_dofs(mesh, plate, std::vector<char>(static_cast<std::size_t>(mesh.node_count()), 1)));
  const auto faces = fem::boundary_faces(mesh);
  problem.set_fixed_dofs(fem::node_dofs(fem::face_nodes_where(mesh, faces, [](const Eigen::Vector3d& c) {
    const bool near_x = c.x() < 50 || c.x() > 950, near_y = c.y() < 50 || c.y() > 950;
    return c.z() < 1e-9 && near_x && near_y;
  })));

  std::vector<double> remaining(static_cast<std::size_t>(mesh.element_count()), 1.0);
  double previous = 0, assembly = 0, reuse = 0, fresh = 0, fresh_analyze = 0, solve = 0;
  // Stations spread over the first passes (the stride keeps each one different from the last).
  const std::size_t stride = std::max<std::size_t>(1, stations.size() / static_cast<std::size_t>(wanted * 4));
  int measured = 0;
  for (std::size_t k = 0; k < stations.size() && measured < wanted; ++k) {
    removal.sweep(levelset::cutting_polylines(path, timeline, previous, stations[k].path_length, 0.01));
    previous = stations[k].path_length;
    removal.update_remaining(elements, geometry::RemovalCriterion::VolumeFraction, remaining, true);
    if (k % stride != 0) continue;
    problem.set_activity(remaining);
    const double a0 = problem.assembly_seconds(), f0 = problem.solver_stats().factorize_seconds;
    problem.assemble_and_factorize();  // (b): symbolic analysis reused
    assembly += problem.assembly_seconds() - a0;
    reuse += problem.solver_stats().factorize_seconds - f0;
    auto t = std::chrono::steady_clock::now();
    problem.solve();
    solve += seconds_since(t);
    fem::SpdSolver scratch;  // (a): from scratch on the same matrix
    t = std::chrono::steady_clock::now();
    scratch.factorize(problem.stiffness());
    fresh += seconds_since(t);
    fresh_analyze += scratch.stats().analyze_seconds;
    ++measured;
  }
  std::printf("{\n  \"unknowns\": %d,\n  \"stations_measured\": %d,\n  \"profiles\": %zu,\n", mesh.dof_count(), measured, 2 * degrees.size());
  std::printf("  \"assembly_s_per_station\": %.4f,\n  \"refactorize_from_scratch_s_per_station\": %.4f,\n", assembly / measured, fresh / measured);
  std::printf("  \"of_which_symbolic_analysis_s\": %.4f,\n  \"factorize_reusing_analysis_s_per_station\": %.4f,\n", fresh_analyze / measured, reuse / measured);
  std::printf("  \"speedup_from_reuse\": %.3f,\n  \"solve_6_rhs_s_per_station\": %.4f,\n", fresh / reuse, solve / measured);
  std::printf("  \"peak_memory_mb\": %.0f\n}\n", static_cast<double>(peak_memory_bytes()) / 1048576.0);
  return 0;
}
