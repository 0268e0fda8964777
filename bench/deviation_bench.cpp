// A measured blank joining the deviation family (reduce/deviation_family.hpp): a laser scan of
// 10^4 ... 10^6 scattered points over 100 x 100 mm, interpolated onto a 101 x 101 grid from each grid
// point's 4 nearest (inverse distance).
//   build/bench/deviation_bench [--benchmark_format=json]
// MeasuredScan is the whole of add_measured: reading the CSV, the k-d tree, the interpolation.
// FullSearchInterpolation is the search it replaced (every point for every grid point), timed on the
// points already in memory: the CSV reading is left out of it, so the ratio of the two understates
// what the k-d tree saves.
#include "reduce/deviation_family.hpp"

#include <benchmark/benchmark.h>

#include <Eigen/Core>

#include <algorithm>
#include <array>
#include <filesystem>
#include <fstream>
#include <random>
#include <vector>

namespace {

std::vector<Eigen::Vector3d> scattered_scan(int points) {
  std::mt19937 random(11);
  std::uniform_real_distribution<double> across(0, 100), noise(-0.01, 0.01);
  std::vector<Eigen::Vector3d> scan;
  scan.reserve(static_cast<std::size_t>(points));
  for (int k = 0; k < points; ++k) {
    const double x = across(random), y = across(random);
    scan.emplace_back(x, y, 1e-4 * (x - 50) * (y - 50) + noise(random));
  }
  return scan;
}

const drom::reduce::DeviationGrid kGrid{0, 100, 0, 100, 101, 101};

void MeasuredScan(benchmark::State& state) {
  const auto csv = std::filesystem::temp_directory_path() / ("drom_bench_scan_" + std::to_string(state.range(0)) + ".csv");
  {
    std::ofstream out(csv);
    out.precision(10);
    for (const auto& p : scattered_scan(static_cast<int>(state.range(0)))) out << p.x() << "," << p.y() << "," << p.z() << "\n";
  }
  for (auto _ : state) {
    drom::reduce::DeviationFamily family(kGrid);
    family.add_measured(csv);
    benchmark::DoNotOptimize(family.snapshots().data());
  }
  std::filesystem::remove(csv);
  state.counters["points"] = static_cast<double>(state.range(0));
}

void FullSearchInterpolation(benchmark::State& state) {
  const auto scan = scattered_scan(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    Eigen::VectorXd values(kGrid.size());
    for (int j = 0; j < kGrid.ny; ++j)
      for (int i = 0; i < kGrid.nx; ++i) {
        const double x = kGrid.x(i), y = kGrid.y(j);
        std::array<std::pair<double, double>, 4> best;
        best.fill({1e300, 0});
        for (const auto& p : scan) {
          const double d2 = (p.x() - x) * (p.x() - x) + (p.y() - y) * (p.y() - y);
          if (d2 < best[3].first) {
            best[3] = {d2, p.z()};
            std::sort(best.begin(), best.end());
          }
        }
        double w = 0, v = 0;
        for (const auto& [d2, z] : best) w += 1 / d2, v += z / d2;
        values[kGrid.index(i, j)] = v / w;
      }
    benchmark::DoNotOptimize(values.data());
  }
  state.counters["points"] = static_cast<double>(state.range(0));
}

}  // namespace

BENCHMARK(MeasuredScan)->Arg(10'000)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond);
BENCHMARK(FullSearchInterpolation)->Arg(10'000)->Arg(100'000)->Arg(1'000'000)->Unit(benchmark::kMillisecond)->Iterations(1);
BENCHMARK_MAIN();
