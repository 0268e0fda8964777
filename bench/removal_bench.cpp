// Level-set material removal: time and memory per station versus voxel size and path length.
// A flat end mill (R 12.5) clears one-way passes at 2 mm depth in a 10 mm plate; a station is 25 mm
// of cutting travel. Also: the whole flat-plate pocket of the seed (600 x 600 x 2, 813 stations).
//   build/bench/removal_bench --benchmark_format=json     (results: docs/benchmarks.md)
#include "levelset/material_removal.hpp"
#include "paths/cutter/tool_assembly.hpp"
#include "levelset/pocket_toolpath.hpp"

#include <benchmark/benchmark.h>

#include <cmath>

using namespace drom::levelset;
using drom::paths::ToolAssembly;
using drom::geometry::PartShape;

namespace {

void run_pocket(benchmark::State& state, double voxel, double pocket_side) {
  const PartShape plate = PartShape::plate(pocket_side + 400, pocket_side + 400, 10);
  const ToolAssembly tool = ToolAssembly::flat(12.5, 30);
  const Toolpath path = pocket_toolpath(plate, {200, 200, pocket_side, pocket_side, 2}, tool, {PocketStrategy::OneWay, 20, 10, 2, 5, 0.01});
  const PathTimeline timeline(path);
  const auto stations = stations_by_spacing(path, timeline, 25);
  double volume = 0;
  std::size_t memory = 0, voxels = 0;
  for (auto _ : state) {
    MaterialRemoval removal(Workpiece::from_shape(plate), tool, voxel);
    double previous = 0;
    for (const auto& s : stations) {
      removal.sweep(cutting_polylines(path, timeline, previous, s.path_length, 0.01));
      previous = s.path_length;
    }
    volume = removal.removed_volume();
    memory = removal.memory_bytes();
    voxels = removal.active_voxels();
  }
  state.counters["stations"] = static_cast<double>(stations.size());
  state.counters["path_length_mm"] = timeline.length();
  state.counters["level_set_mb"] = static_cast<double>(memory) / 1048576.0;
  state.counters["active_voxels"] = static_cast<double>(voxels);
  // The pocket less the four corners a round tool cannot reach.
  const double exact = pocket_side * pocket_side * 2 - 4 * (1 - M_PI / 4) * tool.cutter.radius * tool.cutter.radius * 2;
  state.counters["volume_error_pct"] = 100 * (volume / exact - 1);
}

void BM_RemovalVoxelSize(benchmark::State& state) { run_pocket(state, 1.0 / static_cast<double>(state.range(0)), 150); }
void BM_RemovalPathLength(benchmark::State& state) { run_pocket(state, 0.5, static_cast<double>(state.range(0))); }

}  // namespace

// voxel = 1 / arg mm on a 150 mm pocket; then pockets of growing side at 0.5 mm (600 = the seed's).
BENCHMARK(BM_RemovalVoxelSize)->Arg(1)->Arg(2)->Arg(4)->Arg(8)->Unit(benchmark::kSecond)->Iterations(1);
BENCHMARK(BM_RemovalPathLength)->Arg(150)->Arg(300)->Arg(600)->Unit(benchmark::kSecond)->Iterations(1);

BENCHMARK_MAIN();
