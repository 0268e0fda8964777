#pragma once
// How a shape of the family is handed to drom copy and judged (issue 45), one place for the tests
// (tests/paths/copy/shape_family_test.cpp) and the bench (bench/shape_family_bench.cpp), so the bench
// holds the shapes to the very bounds the tests do: the scan as a PLY, the tools as drom's defaults
// are (ball D6 for the finishing, flat D10 for the roughing, on a D53 holder 40 mm out), the truth
// the checker cuts against, the allowance at an open sheet's edge and what counts as reached.
#include "paths/copy/copy_run.hpp"
#include "tests/paths/copy/independent_checker.hpp"
#include "tests/paths/copy/shape_family.hpp"

#include <Eigen/Core>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <vector>

namespace drom::tests::judging {

constexpr double kTu = 0.01;  // drom copy's default chord tolerance

// The scan as a scanner would hand it over: an ascii PLY of its points, written apart from drom.
inline void write_scan(const std::filesystem::path& file, const family::Shape& s) {
  std::ofstream out(file);
  out << "ply\nformat ascii 1.0\nelement vertex " << s.scan.points.size() << "\nproperty double x\nproperty double y\nproperty double z\nend_header\n";
  char line[128];
  for (const auto& p : s.scan.points) {
    std::snprintf(line, sizeof line, "%.6f %.6f %.6f\n", p.x(), p.y(), p.z());
    out << line;
  }
}

inline checker::ToolSpec finishing_tool() {
  checker::ToolSpec t;
  t.kind = checker::ToolSpec::Kind::ball, t.radius = 3, t.corner = 3, t.gauge_length = 40, t.holder_radius = 26.5;
  return t;
}

inline checker::ToolSpec roughing_tool() {
  checker::ToolSpec t;
  t.kind = checker::ToolSpec::Kind::flat, t.radius = 5, t.corner = 0, t.gauge_length = 40, t.holder_radius = 26.5;
  return t;
}

// drom copy on `dir`/scan.ply into `dir`/copy, with the default settings and the stock as the shop
// states it: its base's top is the table the part stands on, z = 0.
inline paths::CopyRunOptions copy_options(const std::filesystem::path& dir) {
  paths::CopyRunOptions o;
  o.cloud = dir / "scan.ply", o.out = dir / "copy", o.quiet = true;
  o.overrides = {"stock.base_top=0"};
  return o;
}

struct Truth {
  std::vector<Eigen::Vector3d> scan;   // the scan without its stray points
  std::vector<Eigen::Vector3d> solid;  // every face of the solid, the hidden sides and the stock's base
  // Where the scan ends, the part's true edge lies somewhere in the next gap: the true points within
  // `edge_band` of it are judged apart, held to Tu plus `edge_allowance` (the sag a ball takes over a
  // spacing and three noise deviations; drom keeps the part's side beyond the rim, geometry/cloud_rim);
  // everywhere else, every face hidden or shown, to Tu.
  double edge_band = 0, edge_allowance = 0;
};

// The stock's base is the cloud's box grown by the stock margin of 5 mm, as drom's default stock is.
inline Truth truth_of(const family::Shape& shape) {
  Truth t;
  t.scan.assign(shape.scan.points.begin(), shape.scan.points.end() - static_cast<long>(shape.outliers));
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300), hi = -lo;
  for (const auto& p : t.scan) lo = lo.cwiseMin(p), hi = hi.cwiseMax(p);
  t.solid = shape.scanned_truth.points;
  t.solid.insert(t.solid.end(), shape.hidden_truth.points.begin(), shape.hidden_truth.points.end());
  const auto base = checker::base_points(lo.head<2>().array() - 5, hi.head<2>().array() + 5, 0, -5, 0.25);
  t.solid.insert(t.solid.end(), base.begin(), base.end());
  t.edge_band = 1.5 * shape.spacing;
  t.edge_allowance = shape.spacing * shape.spacing / (8 * 3) + 3 * shape.noise;
  return t;
}

// Reached (the finishing passed there): within the scallop bound, the chord tolerance, six noise
// deviations (drom rides the noise's highest points, and stays above what it cannot tell), twice the
// sag a ball may take between points `spacing` apart, and 0.05 mm, of the true surface. A point no
// pass reached is a tool radius or more from every pass. Near an open sheet's edge the scan cannot
// tell where the part ends better than a few spacings (drom keeps its side three spacings out): not
// judged there.
inline checker::CoverageSettings coverage_settings(const family::Shape& shape) {
  checker::CoverageSettings c;
  c.tool = finishing_tool();
  c.reached = 0.005 + kTu + 6 * shape.noise + shape.spacing * shape.spacing / (2 * 3) + 0.05;
  c.unsure = shape.hidden_truth.points;
  c.unsure_radius = 3.5 * shape.spacing;
  return c;
}

}  // namespace drom::tests::judging
