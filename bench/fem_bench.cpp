// Assembly and CHOLMOD factorization of the elastic stiffness versus the number of unknowns.
// Plates 1000 x 1000 x 10 mm (hex20, nz = 5) of growing in-plane resolution, and tet10 meshes of
// 50 L x 50 L x 10 mm blocks (L = 1..3, layer facet at 8 mm, tets up to 8 mm^3) (every tet has its own shape: no element cache).
//   build/bench/fem_bench --benchmark_format=json     (results: docs/benchmarks.md)
#include "fem/element_operators.hpp"
#include "fem/spd_solver.hpp"
#include "fem/stiffness_pattern.hpp"
#include "fem/structured_mesh.hpp"
#include "fem/tet_mesh.hpp"
#include "support/resources.hpp"

#include <benchmark/benchmark.h>

#include <map>

using namespace drom::fem;

namespace {

const Material kAluminium{71700, 0.33};

const Mesh& plate_mesh(int n) {
  static std::map<int, Mesh> meshes;
  auto it = meshes.find(n);
  if (it == meshes.end()) it = meshes.emplace(n, make_structured_hex_mesh(PartShape::plate(1000, 1000, 10), {n, n, 5, 1.0})).first;
  return it->second;
}

const Mesh& tet_mesh(int level) {
  static std::map<int, Mesh> meshes;
  auto it = meshes.find(level);
  if (it == meshes.end())
    it = meshes.emplace(level, make_tet_mesh(layered_box_plc({0, 0, 0}, {50.0 * level, 50.0 * level, 10}, {8.0}), {8.0, 1.4, 0})).first;
  return it->second;
}

Eigen::SparseMatrix<double> assemble(const Mesh& mesh, ElementOperators& ops, const StiffnessPattern& pattern) {
  Eigen::SparseMatrix<double> K = pattern.zero_matrix();
  for (int e = 0; e < mesh.element_count(); ++e) pattern.add_element(K, mesh.element(e), ops.stiffness(e), 1.0);
  return K;
}

// Clamp z = 0 so K is definite (the benchmark measures the factorization, not the supports).
void clamp_bottom(const Mesh& mesh, Eigen::SparseMatrix<double>& K) {
  std::vector<char> held(static_cast<std::size_t>(mesh.dof_count()), 0);
  for (int n = 0; n < mesh.node_count(); ++n)
    if (mesh.nodes[static_cast<std::size_t>(n)].z() < 1e-9) held[3 * n] = held[3 * n + 1] = held[3 * n + 2] = 1;
  for (int c = 0; c < K.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(K, c); it; ++it)
      if (held[static_cast<std::size_t>(it.row())] || held[static_cast<std::size_t>(c)]) it.valueRef() = it.row() == c ? 1e5 : 0.0;
}

void counters(benchmark::State& state, const Mesh& mesh, const Eigen::SparseMatrix<double>& K) {
  state.counters["unknowns"] = mesh.dof_count();
  state.counters["elements"] = mesh.element_count();
  state.counters["nnz_lower"] = static_cast<double>(K.nonZeros());
  state.counters["peak_rss_mb"] = static_cast<double>(drom::peak_memory_bytes()) / 1048576.0;
}

void BM_AssemblePlateHex20(benchmark::State& state) {
  const Mesh& mesh = plate_mesh(static_cast<int>(state.range(0)));
  const StiffnessPattern pattern(mesh);
  Eigen::SparseMatrix<double> K;
  for (auto _ : state) {
    ElementOperators ops(mesh, kAluminium);  // fresh cache each time: its fill is part of the cost
    K = assemble(mesh, ops, pattern);
    benchmark::DoNotOptimize(K.valuePtr());
  }
  counters(state, mesh, K);
}

void BM_AssembleBlockTet10(benchmark::State& state) {
  const Mesh& mesh = tet_mesh(static_cast<int>(state.range(0)));
  const StiffnessPattern pattern(mesh);
  Eigen::SparseMatrix<double> K;
  for (auto _ : state) {
    ElementOperators ops(mesh, kAluminium);
    K = assemble(mesh, ops, pattern);
    benchmark::DoNotOptimize(K.valuePtr());
  }
  counters(state, mesh, K);
}

void factorize(benchmark::State& state, const Mesh& mesh) {
  const StiffnessPattern pattern(mesh);
  ElementOperators ops(mesh, kAluminium);
  Eigen::SparseMatrix<double> K = assemble(mesh, ops, pattern);
  clamp_bottom(mesh, K);
  SpdSolver solver;
  for (auto _ : state) {
    solver.factorize(K);  // symbolic analysis on the first iteration only, as in a station loop
  }
  counters(state, mesh, K);
  state.counters["analyze_s"] = solver.stats().analyze_seconds;
  state.counters["factorize_s_each"] = solver.stats().factorize_seconds / solver.stats().factorizations;
  state.counters["cholmod_peak_mb"] = static_cast<double>(solver.stats().factor_peak_bytes) / 1048576.0;
}

void BM_FactorizePlateHex20(benchmark::State& state) { factorize(state, plate_mesh(static_cast<int>(state.range(0)))); }
void BM_FactorizeBlockTet10(benchmark::State& state) { factorize(state, tet_mesh(static_cast<int>(state.range(0)))); }

}  // namespace

BENCHMARK(BM_AssemblePlateHex20)->Arg(10)->Arg(20)->Arg(40)->Arg(60)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_AssembleBlockTet10)->Arg(1)->Arg(2)->Arg(3)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_FactorizePlateHex20)->Arg(10)->Arg(20)->Arg(40)->Arg(60)->Unit(benchmark::kMillisecond)->Iterations(2);
BENCHMARK(BM_FactorizeBlockTet10)->Arg(1)->Arg(2)->Arg(3)->Unit(benchmark::kMillisecond)->Iterations(2);

BENCHMARK_MAIN();
