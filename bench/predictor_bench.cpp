// Latency of the online predictor (issue 6): add_profile with an 800-point laser profile, tool_offset,
// and estimate(), for r = 2 ... 40, on a model the size of the default flat plate's: the 600 x 600 mm
// pocket floor as 24 x 24 Quad8 faces (1825 nodes), 30 one-way passes at 10 mm/s, a station every
// 25 mm (about 780), each basis history kept as 30 separated terms.
//   build/bench/predictor_bench [--benchmark_format=json] [--benchmark_repetitions=5]
// The arguments: r, the time between profiles (ms) and the offset's refresh rate (Hz, 0: none).
// Goals: under 50 us per 800-point profile and under 1 us per offset query at r = 20.
#include "online/predictor.hpp"

#include <benchmark/benchmark.h>

#include <cmath>
#include <limits>
#include <memory>

using namespace drom;

namespace {

constexpr double kFeed = 10, kPass = 60, kCycle = 65, kRadius = 12.5, kFloor = 8;
constexpr int kPasses = 30;

reduce::LightModel plate_sized_model(int r) {
  const int e = 24, n = 2 * e + 1;
  std::vector<int> id(static_cast<std::size_t>(n * n), -1);
  std::vector<Eigen::Vector3d> xyz;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i)
      if (i % 2 == 0 || j % 2 == 0) {  // serendipity: no face centres
        id[static_cast<std::size_t>(j * n + i)] = static_cast<int>(xyz.size());
        xyz.emplace_back(200 + 12.5 * i, 200 + 12.5 * j, kFloor);
      }
  auto at = [&](int i, int j) { return id[static_cast<std::size_t>(j * n + i)]; };
  std::vector<int> faces;
  for (int b = 0; b < e; ++b)
    for (int a = 0; a < e; ++a) {
      const int i = 2 * a, j = 2 * b;
      for (int v : {at(i, j), at(i + 2, j), at(i + 2, j + 2), at(i, j + 2), at(i + 1, j), at(i + 2, j + 1), at(i + 1, j + 2), at(i, j + 1)}) faces.push_back(v);
    }
  Eigen::Matrix3Xd nodes(3, static_cast<Eigen::Index>(xyz.size()));
  for (std::size_t k = 0; k < xyz.size(); ++k) nodes.col(static_cast<Eigen::Index>(k)) = xyz[k];
  reduce::LightModel m;
  m.target = reduce::SurfaceMesh(nodes, faces, 8);
  const Eigen::Index nn = nodes.cols();
  m.target_cut_time.resize(nn);
  for (Eigen::Index k = 0; k < nn; ++k) {
    m.target_cut_time[k] = std::numeric_limits<double>::infinity();
    for (int p = 0; p < kPasses; ++p) {
      const double dy = nodes(1, k) - (200 + 10 + 20 * p);
      if (std::abs(dy) > kRadius) continue;
      m.target_cut_time[k] = p * kCycle + std::max(0.0, nodes(0, k) - 200 - std::sqrt(kRadius * kRadius - dy * dy)) / kFeed;
      break;
    }
  }
  const int stations = static_cast<int>(kPasses * kCycle / 2.5), terms = 30;
  Eigen::VectorXd times = Eigen::VectorXd::LinSpaced(stations + 1, 0, kPasses * kCycle);
  for (int k = 0; k < r; ++k) {
    Eigen::MatrixXd space(nn, terms), time(stations + 1, terms);
    for (int l = 0; l < terms; ++l) {
      for (Eigen::Index q = 0; q < nn; ++q) space(q, l) = std::cos(0.01 * (l + 1) * nodes(0, q) + k) * std::sin(0.013 * (l + 2) * nodes(1, q));
      for (int s = 0; s <= stations; ++s) time(s, l) = std::pow(times[s] / times[stations], 1 + 0.1 * l) / (1 + l);
    }
    m.histories.emplace_back(space, time, times, 0.0);
  }
  m.singular_values = Eigen::VectorXd::Ones(r);
  m.right = Eigen::MatrixXd::Identity(r, r);
  m.prior_sd = Eigen::VectorXd::Ones(r);
  m.shape_nodes = nodes;
  m.shape_faces = faces;
  m.shape_face_nodes = 8;
  m.final_basis = Eigen::MatrixXd::Ones(3 * nn, r);
  m.path.resize(2 * kPasses, 4);
  for (int p = 0; p < kPasses; ++p) {
    m.path.row(2 * p) << 200, 210 + 20 * p, kFloor, p * kCycle;
    m.path.row(2 * p + 1) << 800, 210 + 20 * p, kFloor, p * kCycle + kPass;
  }
  m.tool_radius = kRadius;
  return m;
}

// An 800-point profile across the feed, 50 mm behind the tool, during pass p at time t.
std::vector<online::MeasuredPoint> profile_at(double t) {
  const int p = static_cast<int>(t / kCycle);
  const double x = 200 + (t - p * kCycle) * kFeed - 50, y = 210 + 20 * p;
  std::vector<online::MeasuredPoint> pts;
  for (int i = 0; i < 800; ++i) pts.push_back({x, y - 40 + 80.0 * i / 799, kFloor});
  return pts;
}

// Profiles every `period` s of program time along each pass. The predictor keeps U1 per node and
// stored instant in a small cache, so its cost depends on how far the sheet moves between profiles:
// the cases' sensor reads every 0.1 s at 10 mm/s (1 mm apart); every 1 s is the cold-cache case.
std::vector<double> profile_times(double period = 1.0) {
  std::vector<double> t;
  const int per_pass = static_cast<int>(std::lround(50 / period));
  for (int p = 1; p < kPasses; ++p)
    for (int k = 0; k < per_pass; ++k) t.push_back(p * kCycle + 6 + k * period);
  return t;
}

// The offset a control loop commands as it follows the floor: a smooth ramp of a few hundredths of
// a millimetre, as the cases' corrected runs record it.
double commanded_offset(double t) { return 0.02 * std::sin(t / 7.0) + 0.01 * std::sin(t / 2.3); }

// state.range(1): milliseconds between profiles; state.range(2): the offset's refresh rate (Hz, 0: no
// offset). The cases refresh at 100 Hz, so a cover of the 25 mm tool at 10 mm/s spans 250 offset
// steps, all of which the lowest-cut search has to weigh.
void AddProfile(benchmark::State& state) {
  const auto model = plate_sized_model(static_cast<int>(state.range(0)));
  const double period = static_cast<double>(state.range(1)) / 1000, rate = static_cast<double>(state.range(2));
  const auto times = profile_times(period);
  std::vector<std::vector<online::MeasuredPoint>> profiles;
  for (double t : times) profiles.push_back(profile_at(t));
  auto predictor = std::make_unique<online::Predictor>(model);
  std::size_t i = 0;
  long long used = 0;
  for (auto _ : state) {
    if (i == times.size()) {
      state.PauseTiming();
      predictor = std::make_unique<online::Predictor>(model);
      i = 0;
      state.ResumeTiming();
    }
    if (rate > 0) {
      // The control thread's offsets since the last profile, and the one in force at this profile.
      state.PauseTiming();
      for (double t = i > 0 ? times[i - 1] : 0.0; t < times[i]; t += 1 / rate) predictor->record_offset(t, commanded_offset(std::round(t * rate) / rate));
      state.ResumeTiming();
    }
    used += predictor->add_profile(times[i], {{}, rate > 0 ? commanded_offset(times[i]) : 0.0}, profiles[i]).used;
    ++i;
  }
  state.counters["points_used_per_profile"] = static_cast<double>(used) / static_cast<double>(state.iterations());
  state.counters["learned"] = predictor->estimate().learned ? 1 : 0;
}

void ToolOffset(benchmark::State& state) {
  const auto model = plate_sized_model(static_cast<int>(state.range(0)));
  online::Predictor predictor(model);
  for (double t : profile_times()) predictor.add_profile(t, {}, profile_at(t));
  if (!predictor.estimate().learned) state.SkipWithError("not learned: the offsets would be trivial zeros");
  double t = kCycle, sum = 0;
  for (auto _ : state) {
    sum += predictor.tool_offset(t);
    t += 1e-3;
    if (t > kPasses * kCycle) t = kCycle;
  }
  benchmark::DoNotOptimize(sum);
}

void Estimate(benchmark::State& state) {
  const auto model = plate_sized_model(static_cast<int>(state.range(0)));
  online::Predictor predictor(model);
  for (double t : profile_times()) predictor.add_profile(t, {}, profile_at(t));
  for (auto _ : state) benchmark::DoNotOptimize(predictor.estimate());
}

}  // namespace

BENCHMARK(AddProfile)->ArgsProduct({{2, 5, 10, 20, 30, 40}, {100, 1000}, {0, 100}})->ArgNames({"r", "period_ms", "offset_hz"})->Unit(benchmark::kMicrosecond);
BENCHMARK(ToolOffset)->Arg(2)->Arg(5)->Arg(10)->Arg(20)->Arg(30)->Arg(40)->Unit(benchmark::kNanosecond);
BENCHMARK(Estimate)->Arg(2)->Arg(20)->Arg(40)->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
