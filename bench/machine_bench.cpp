// machine/: the time prediction of a 100 000-block 5-axis program (goal: under 0.5 s here) and the
// inverse kinematics of 10^6 poses (goal: under 0.1 s), on the table-table machine.
// The program: zigzag passes over the saddle z = (x² - y²) / 200 across 160 x 160 mm, CL points every
// 0.25 mm (1 mm step-over), the tool tilted 3° across the feed, so C swings near the singularity.
//   build/bench/machine_bench --benchmark_format=json     (results: docs/machine.md)
#include "machine/cl_data.hpp"
#include "machine/feed_prediction.hpp"

#include <Eigen/Geometry>
#include <benchmark/benchmark.h>
#include <tbb/global_control.h>

#include <cmath>
#include <cstdio>

using namespace drom::machine;

namespace {

volatile double sink = 0;

ClProgram saddle_zigzag(std::size_t points) {
  ClProgram cl;
  const double c = 100, tilt = 3 * M_PI / 180, step = 0.25, width = 160;
  const int per_pass = static_cast<int>(width / step) + 1;
  for (std::size_t k = 0; k < points; ++k) {
    // The zigzag covers the square in 161 passes, then starts over (a million points: six times).
    const int pass = static_cast<int>(k / per_pass) % 161, i = static_cast<int>(k % per_pass);
    const double y = -80 + 1.0 * pass, x = pass % 2 ? 80 - step * i : -80 + step * i;
    const Eigen::Vector3d n = Eigen::Vector3d(-x / c, y / c, 1).normalized();
    const Eigen::Vector3d f = Eigen::Vector3d(1, 0, x / c).normalized();
    ClPoint p;
    p.pose.tip = {x, y, (x * x - y * y) / (2 * c)};
    p.pose.axis = (std::cos(tilt) * n + std::sin(tilt) * n.cross(f).normalized()).normalized();
    p.feed = 3000;
    p.rapid = k == 0;
    cl.points.push_back(p);
  }
  return cl;
}

void TimePrediction(benchmark::State& state) {
  const Kinematics kin(load_machine("ucp710_like"));
  const ClOnMachine on = cl_to_machine_program(saddle_zigzag(static_cast<std::size_t>(state.range(0)) + 1), kin);
  double cycle = 0, programmed = 0, anchors = 0, passes = 0;
  for (auto _ : state) {
    const FeedPrediction p = predict_feed(on.program, kin);
    cycle = p.cycle_time, programmed = p.programmed_time, anchors = p.anchors, passes = p.iterations;
    benchmark::ClobberMemory();
  }
  state.counters["blocks"] = static_cast<double>(on.program.blocks.size());
  state.counters["cycle_time_s"] = cycle;
  state.counters["programmed_time_s"] = programmed;
  state.counters["anchors"] = anchors;
  state.counters["planner_passes"] = passes;
  state.counters["violations"] = static_cast<double>(on.joints.violations.size());
}
BENCHMARK(TimePrediction)->Arg(100000)->Unit(benchmark::kMillisecond)->MinTime(2);

void InverseKinematics(benchmark::State& state) {
  const Kinematics kin(load_machine("ucp710_like"));
  const ClProgram cl = saddle_zigzag(static_cast<std::size_t>(state.range(0)));
  std::vector<ClPose> poses;
  for (const auto& p : cl.points) poses.push_back(p.pose);
  std::size_t violations = 0;
  for (auto _ : state) {
    const JointPath path = inverse_path(kin, poses);
    violations = path.violations.size();
    benchmark::DoNotOptimize(path.joints.back());
  }
  state.counters["poses"] = static_cast<double>(poses.size());
  state.counters["violations"] = static_cast<double>(violations);
}
BENCHMARK(InverseKinematics)->Arg(1000000)->Unit(benchmark::kMillisecond)->MinTime(2);

// The same path on one thread: its CPU time bounds the wall time on an idle machine of any core count,
// and stays meaningful when other work loads the machine (the figure quoted in docs/machine.md).
void InverseKinematicsOneThread(benchmark::State& state) {
  const tbb::global_control one_thread(tbb::global_control::max_allowed_parallelism, 1);
  const Kinematics kin(load_machine("ucp710_like"));
  const ClProgram cl = saddle_zigzag(static_cast<std::size_t>(state.range(0)));
  std::vector<ClPose> poses;
  for (const auto& p : cl.points) poses.push_back(p.pose);
  for (auto _ : state) {
    const JointPath path = inverse_path(kin, poses);
    benchmark::DoNotOptimize(path.joints.back());
  }
}
BENCHMARK(InverseKinematicsOneThread)->Arg(1000000)->Unit(benchmark::kMillisecond)->MinTime(2);

// Both branches of every pose, with their trigonometry (what a path pays without the branch split).
void InverseBothBranches(benchmark::State& state) {
  const Kinematics kin(load_machine("ucp710_like"));
  const ClProgram cl = saddle_zigzag(static_cast<std::size_t>(state.range(0)));
  for (auto _ : state) {
    double sum = 0;
    for (const auto& p : cl.points) sum += kin.inverse(p.pose).joints[0][4];
    sink = sum;  // (DoNotOptimize on a double misbehaves with GCC 12 and Debian's benchmark 1.7: see shared/deps.md)
  }
}
BENCHMARK(InverseBothBranches)->Arg(1000000)->Unit(benchmark::kMillisecond)->MinTime(2);

}  // namespace

BENCHMARK_MAIN();
