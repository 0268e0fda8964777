// geometry/: evaluating a patch with its first and second derivatives, drom's evaluator against
// OpenCASCADE's Geom_BSplineSurface::D2 on the same surface (Choi's bicubic Bézier patch as a
// B-spline), 10^6 points each; path planning evaluates surfaces hundreds of thousands of times per
// black-box run, which is why geometry/ has its own.   build/bench/geometry_bench --benchmark_format=json
#include "geometry/nurbs_surface.hpp"
#include "tests/geometry/test_surfaces.hpp"

#include <Geom_BSplineSurface.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <benchmark/benchmark.h>

namespace {

constexpr int kSide = 1000;  // 10^6 points on a grid

void DromDerivatives(benchmark::State& state) {
  const auto s = drom::tests::choi_surface();
  double sink = 0;
  for (auto _ : state) {
    for (int a = 0; a < kSide; ++a)
      for (int b = 0; b < kSide; ++b) {
        const auto d = s.derivatives((a + 0.5) / kSide, (b + 0.5) / kSide);
        sink += d.duv.x();
      }
    benchmark::DoNotOptimize(sink);
  }
  state.counters["points"] = kSide * kSide;
}

void OcctD2(benchmark::State& state) {
  const auto s = drom::tests::choi_surface();
  TColgp_Array2OfPnt poles(1, s.count_u(), 1, s.count_v());
  for (int i = 0; i < s.count_u(); ++i)
    for (int j = 0; j < s.count_v(); ++j) {
      const auto& p = s.points()[static_cast<std::size_t>(i * s.count_v() + j)];
      poles.SetValue(i + 1, j + 1, gp_Pnt(p.x(), p.y(), p.z()));
    }
  TColStd_Array1OfReal knots(1, 2);
  knots.SetValue(1, 0);
  knots.SetValue(2, 1);
  TColStd_Array1OfInteger mults(1, 2);
  mults.SetValue(1, s.count_u());
  mults.SetValue(2, s.count_u());
  TColStd_Array1OfInteger mults_v(1, 2);
  mults_v.SetValue(1, s.count_v());
  mults_v.SetValue(2, s.count_v());
  const Handle(Geom_BSplineSurface) occt = new Geom_BSplineSurface(poles, knots, knots, mults, mults_v, s.count_u() - 1, s.count_v() - 1);
  double sink = 0;
  gp_Pnt p;
  gp_Vec du, dv, duu, dvv, duv;
  for (auto _ : state) {
    for (int a = 0; a < kSide; ++a)
      for (int b = 0; b < kSide; ++b) {
        occt->D2((a + 0.5) / kSide, (b + 0.5) / kSide, p, du, dv, duu, dvv, duv);
        sink += duv.X();
      }
    benchmark::DoNotOptimize(sink);
  }
  state.counters["points"] = kSide * kSide;
}

}  // namespace

BENCHMARK(DromDerivatives)->Unit(benchmark::kMillisecond);
BENCHMARK(OcctD2)->Unit(benchmark::kMillisecond);
BENCHMARK_MAIN();
