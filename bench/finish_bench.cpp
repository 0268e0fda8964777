// paths/: the two goals of issue 22, printed as JSON (results: docs/finishing.md).
//  - path generation for one zoning at 80 x 80 and a 0.5 mm mesh step (goal: under 50 ms): Rubio
//    cut into K-means' K = 3 zones, each along its steepest slope, torus R5 r2, sh 0.01 mm; the fast
//    (iso-line) variant the black box uses, and for reference the exact (Newton) variant;
//  - a full 3-axis optimisation on Rubio, K = 2..10 at 1000 evaluations per K, one thread (goal:
//    under 60 s; the seed: about 35 min per surface).
//   build/bench/finish_bench            (add --skip-optimisation for the path part alone)
#include "paths/finish/finish_optimizer.hpp"
#include "tests/geometry/test_surfaces.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <vector>

using namespace drom::paths;

namespace {

double seconds_since(std::chrono::steady_clock::time_point t0) { return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count(); }

// The median of `repeats` runs of f, in seconds.
template <class F>
double median_time(int repeats, F&& f) {
  std::vector<double> t;
  for (int r = 0; r < repeats; ++r) {
    const auto t0 = std::chrono::steady_clock::now();
    f();
    t.push_back(seconds_since(t0));
  }
  std::nth_element(t.begin(), t.begin() + repeats / 2, t.end());
  return t[static_cast<std::size_t>(repeats / 2)];
}

}  // namespace

int main(int argc, char** argv) {
  const bool skip_optimisation = argc > 1 && std::strcmp(argv[1], "--skip-optimisation") == 0;
  const auto surface = drom::tests::rubio_surface();
  FinishingSettings fs;
  fs.tool = Tool{ToolKind::torus, 5, 2};
  fs.stepover = StepoverModel::seed;
  fs.accounting = Accounting::seed;

  auto t0 = std::chrono::steady_clock::now();
  const FinishingProblem problem = make_problem(surface, {}, fs, 80, 0.5);
  const double setup_time = seconds_since(t0);
  const Zones zones = connected_zones(kmeans(problem.samples, surface, 3, ClusteringSettings{}), 80, 80);
  std::vector<ZoneSetup> setups;
  for (const auto& z : describe_zones(problem.samples, zones)) setups.push_back(three_axis_setup(z.steepest_azimuth));
  std::size_t passes = 0;
  const double fast = median_time(21, [&] { passes = static_cast<std::size_t>(plan_finishing(problem.mesh, zones, setups, fs).pass_count()); });
  FinishingSettings exact = fs;
  exact.exact = true;
  exact.stepover = StepoverModel::curved;
  exact.accounting = Accounting::machine;
  const double exact_time = median_time(5, [&] { plan_finishing(problem.mesh, zones, setups, exact); });
  FinishingSettings run_out = exact;
  run_out.run_out = 20 * run_out.tool.radius;  // drom finish's default
  const double run_out_time = median_time(5, [&] { plan_finishing(problem.mesh, zones, setups, run_out); });
  // What drom finish's search plans per evaluation: the fast variant with the curved step-over and run-outs.
  FinishingSettings search = run_out;
  search.exact = false;
  const double search_time = median_time(21, [&] { plan_finishing(problem.mesh, zones, setups, search); });
  std::printf("{\n  \"problem_setup_s\": %.4f,\n  \"path_generation\": {\"zones\": %d, \"passes\": %zu, \"fast_variant_ms\": %.2f, \"exact_variant_ms\": %.2f, "
              "\"exact_with_run_outs_ms\": %.2f, \"search_variant_ms\": %.2f, \"goal_ms\": 50},\n",
              setup_time, zones.count(), passes, 1e3 * fast, 1e3 * exact_time, 1e3 * run_out_time, 1e3 * search_time);
  if (skip_optimisation) {
    std::printf("  \"optimisation\": null\n}\n");
    return 0;
  }
  OptimizerSettings os;
  os.budget = 1000;
  std::printf("  \"optimisation\": {\"surface\": \"rubio\", \"mode\": \"3-axis\", \"budget_per_K\": 1000, \"per_K\": [\n");
  t0 = std::chrono::steady_clock::now();
  const std::clock_t cpu0 = std::clock();  // the machine is shared: CPU time says what wall time would be alone
  for (int k = 2; k <= 10; ++k) {
    const auto tk = std::chrono::steady_clock::now();
    const KOptimum r = optimize_clusters(problem, k, os);
    std::printf("    {\"K\": %d, \"f0_s\": %.2f, \"f_star_s\": %.2f, \"eta\": %.4f, \"spent\": %.0f, \"wall_s\": %.2f}%s\n", k, r.start_time, r.best_time, r.gain(), r.spent,
                seconds_since(tk), k < 10 ? "," : "");
    std::fflush(stdout);
  }
  std::printf("  ], \"total_wall_s\": %.2f, \"total_cpu_s\": %.2f, \"goal_s\": 60}\n}\n", seconds_since(t0), static_cast<double>(std::clock() - cpu0) / CLOCKS_PER_SEC);
}
