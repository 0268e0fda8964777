// Issue 45's benchmark, as JSON: drom copy on the family of generated shapes (tests/paths/copy/
// shape_family.hpp: caps, domes, saddles, steps, undercuts, holes, ridges; noise 0-0.1 mm, spacing
// 0.1-1 mm, stray points), the default settings as the tests use them, each shape's copy timed as a
// whole (wall and CPU), and its posted CL files judged by the independent checker
// (tests/paths/copy/independent_checker.hpp): the deepest any move takes the whole tool into the scan
// and into the true solid (away from the scan's open edge, and near it), the coverage of the
// machinable true points, the scallop. The tests run one shape per kind; this runs as many as asked.
//   build/bench/shape_family_bench [shapes per kind, default 5] [seed, default 9191] [kind: only those]
//   (DROM_BENCH_KEEP=1 keeps every shape's scan.ply and copy folder under the temporary directory)
// A shape meets the checks as the tests hold them (tests/paths/copy/shape_family_test.cpp): no move
// deeper than Tu into the scan, none into the true solid, none at the open edge past its allowance,
// 99 % of the machinable true points reached, no packet refused by drom's own check.
#include "support/resources.hpp"
#include "tests/paths/copy/shape_judging.hpp"

#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <string>
#include <unistd.h>

namespace fs = std::filesystem;
using namespace drom;
using namespace drom::tests;

int main(int argc, char** argv) {
  const int per_kind = argc > 1 ? std::atoi(argv[1]) : 5;
  const unsigned seed = argc > 2 ? static_cast<unsigned>(std::atoi(argv[2])) : 9191u;
  const std::string only = argc > 3 ? argv[3] : "";
  const bool keep = std::getenv("DROM_BENCH_KEEP") != nullptr;  // keep each shape's scan and copy to look at
  const fs::path scratch = fs::temp_directory_path() / ("drom_shape_family_bench_" + std::to_string(::getpid()));
  fs::create_directories(scratch);
  const auto family = family::make_family(per_kind, seed, 60000);
  const checker::ToolSpec ball = judging::finishing_tool();
  constexpr double kTu = judging::kTu;
  std::printf("{\n  \"per_kind\": %d,\n  \"seed\": %u,\n  \"shapes\": [\n", per_kind, seed);
  int met = 0, run = 0;
  for (std::size_t k = 0; k < family.size(); ++k) {
    const family::Shape& shape = family[k];
    if (!only.empty() && only != family::kind_name(shape.kind)) continue;
    const fs::path dir = scratch / std::to_string(k);
    fs::create_directories(dir);
    judging::write_scan(dir / "scan.ply", shape);
    const paths::CopyRunOptions o = judging::copy_options(dir);
    const auto start = std::chrono::steady_clock::now();
    const double cpu0 = process_cpu_seconds();
    const nlohmann::json s = paths::run_copy(o);
    const double wall = seconds_since(start), cpu = process_cpu_seconds() - cpu0;
    // The checker, as the test runs it.
    const judging::Truth truth = judging::truth_of(shape);
    Eigen::Vector3d worst_truth = Eigen::Vector3d::Zero();
    double deepest_cloud = 0, deepest_truth = 0, deepest_edge = 0, largest_tilt = 0;
    long long over = 0;
    int refused = 0;  // packets whose program drom did not post (its own check found a move over Tu)
    std::vector<checker::ClFile> finishing;
    const int packets = s["grouping"]["packets"].get<int>();
    for (int p = 0; p < packets; ++p) {
      const fs::path cl = o.out / ("packet_" + std::to_string(p + 1)) / "finishing_cl.csv";
      largest_tilt = std::max(largest_tilt, s["packets"][static_cast<std::size_t>(p)]["tilt_deg"].get<double>());
      for (const char* op : {"finishing", "roughing"})
        refused += s["packets"][static_cast<std::size_t>(p)].contains(op) && s["packets"][static_cast<std::size_t>(p)][op].contains("refused");
      if (!fs::exists(cl)) continue;
      finishing.push_back(checker::read_cl_csv(cl));
      const checker::PathResult r = checker::check_path(finishing.back(), ball, truth.scan, truth.solid, kTu, shape.open_edge, truth.edge_band, kTu + truth.edge_allowance);
      if (r.deepest_truth > deepest_truth) worst_truth = r.worst_truth_part;
      deepest_cloud = std::max(deepest_cloud, r.deepest_cloud), deepest_truth = std::max(deepest_truth, r.deepest_truth);
      if (r.deepest_at_edge > deepest_edge && r.deepest_at_edge > kTu + truth.edge_allowance)
        std::fprintf(stderr, "%s, packet %d: %.4f mm at the open edge, true point (%.3f, %.3f, %.3f)\n", shape.name.c_str(), p + 1, r.deepest_at_edge, r.worst_edge_part.x(), r.worst_edge_part.y(),
                     r.worst_edge_part.z());
      deepest_edge = std::max(deepest_edge, r.deepest_at_edge);
      if (r.over_cloud > 0 && over == 0) std::fprintf(stderr, "%s, packet %d: %s\n", shape.name.c_str(), p + 1, r.first_over.c_str());
      over += r.over_cloud;  // rapids leaving a cut node inherit its depth in the truth: judged by the deepest
    }
    const checker::CoverageSettings c = judging::coverage_settings(shape);
    const checker::CoverageResult cov = checker::check_coverage(finishing, shape.scanned_truth.points, shape.scanned_truth.normals, truth.solid, c);
    const bool ok = over == 0 && refused == 0 && deepest_truth <= kTu + 1e-6 && deepest_edge <= kTu + truth.edge_allowance + 1e-6 && cov.coverage >= 0.99;
    const char* separator = run > 0 ? ",\n" : "";
    met += ok, ++run;
    std::printf("%s    {\"name\": \"%s\", \"scan_points\": %zu, \"packets\": %d, \"largest_tilt_deg\": %.0f, \"wall_s\": %.2f, \"cpu_s\": %.2f, "
                "\"deepest_into_scan_mm\": %.4f, \"deepest_into_truth_mm\": %.4f, \"deepest_truth_at\": [%.2f, %.2f, %.2f], \"deepest_at_open_edge_mm\": %.4f, \"moves_over_into_scan\": %lld, \"refused\": %d, "
                "\"coverage\": %.4f, \"scallop_mm\": %.4f, \"met\": %s}",
                separator, shape.name.c_str(), shape.scan.points.size() - shape.outliers, packets, largest_tilt, wall, cpu, deepest_cloud, deepest_truth, worst_truth.x(), worst_truth.y(), worst_truth.z(), deepest_edge, over, refused,
                cov.coverage, cov.scallop, ok ? "true" : "false");
    std::fflush(stdout);
    if (keep) {  // the machinable true points no pass reached, to look at beside the copy
      std::ofstream missed(dir / "missed.csv");
      missed << "x,y,z\n";
      for (const auto& p : cov.missed) missed << p.x() << ',' << p.y() << ',' << p.z() << '\n';
    } else {
      fs::remove_all(dir);
    }
  }
  std::printf("\n  ],\n  \"met\": %d,\n  \"shapes_run\": %d\n}\n", met, run);
  if (!keep) fs::remove_all(scratch);
  else std::fprintf(stderr, "shape_family_bench: the scans and copies are kept in %s\n", scratch.c_str());
  return 0;
}
