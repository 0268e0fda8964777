// The zoning scans behind docs/finishing.md §3-4 ("why no weighting reproduces the seed's Rubio
// rows", "Rubio 3-axis, K = 4, measured"): partitions of the seed's test surfaces timed in the seed's
// step-over model and accounting with the torus R5 r2 (sh 0.01 mm), as JSON lines.
//
//   zoning_scan best-directions rubio|choi K LEVELS   K-means over omega on a LEVELS^4 grid of [0, 1]^4,
//                                                     each distinct partition with every zone in its best
//                                                     direction (3 deg scan, refined to 0.25 deg)
//   zoning_scan shapes rubio|choi                     strips by quantiles of u, v, s, theta (K = 1..5) and
//                                                     two zones split by slope, best directions
//   zoning_scan weights rubio|choi                    K = 3 partitions over a wide range of feature weights,
//                                                     each zone along its steepest slope (time, length, lambda ratios)
//   zoning_scan seed-protocol rubio|choi              K-means and Ward, K = 3, omega = (1, 1, w_s, w_theta):
//                                                     steepest with the torus, principal with the better tool
//
// Minutes each (best-directions at 9 levels: about an hour on one core).
#include "paths/finish/clustering.hpp"
#include "paths/finish/finish_optimizer.hpp"
#include "paths/finish/pca.hpp"
#include "paths/finish/zone_machining.hpp"
#include "tests/geometry/test_surfaces.hpp"

#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>
#include <numbers>
#include <set>
#include <string>

namespace {

using namespace drom::paths;
using nlohmann::json;
constexpr double kDeg = std::numbers::pi / 180;

struct Scan {
  FinishingProblem problem;
  FinishingSettings torus, ball;

  explicit Scan(bool rubio) : problem(make_problem(rubio ? drom::tests::rubio_surface() : drom::tests::choi_surface(), {}, seed_settings(), 80, 0.5)) {
    torus = problem.settings;
    ball = torus;
    ball.tool = Tool{ToolKind::ball, 5, 5};
  }

  static FinishingSettings seed_settings() {
    FinishingSettings fs;
    fs.tool = Tool{ToolKind::torus, 5, 2};
    fs.stepover = StepoverModel::seed;
    fs.accounting = Accounting::seed;
    return fs;
  }

  int samples() const { return problem.samples.size(); }
  const Eigen::Vector4d& feature(int i) const { return problem.samples.features[static_cast<std::size_t>(i)]; }

  Zones zones(const std::vector<int>& labels) const { return connected_zones(labels, problem.samples.cells_u, problem.samples.cells_v); }

  std::vector<int> cells_of(const Zones& z, int k) const {
    std::vector<int> cells;
    for (int c = 0; c < problem.mesh.cell_count(); ++c) {
      const int s = problem.mesh.sample_cell[static_cast<std::size_t>(c)];
      if (s >= 0 && z.zone[static_cast<std::size_t>(s)] == k) cells.push_back(c);
    }
    return cells;
  }

  ZoneMachining machine(const std::vector<int>& cells, double azimuth, const FinishingSettings& fs) const {
    return machine_zone(problem.mesh, cells, 0, three_axis_setup(azimuth), fs);
  }

  // The zone's least time over feed directions: every 3 deg, then a pattern search down to 0.25 deg.
  // A direction whose planes all miss a sliver of a zone plans nothing there: it does not count, and
  // a zone no direction plans (a few cells) counts 0 s.
  std::pair<double, double> best_direction(const std::vector<int>& cells) const {
    const auto time_at = [&](double deg) {
      const ZoneMachining m = machine(cells, deg * kDeg, torus);
      return m.passes.empty() ? std::numeric_limits<double>::infinity() : m.time();
    };
    double best = std::numeric_limits<double>::infinity(), at = 0;
    for (int a = -90; a < 90; a += 3)
      if (const double t = time_at(a); t < best) best = t, at = a;
    if (!std::isfinite(best)) return {0.0, 0.0};
    for (double step = 1.5; step >= 0.25; step /= 2)
      for (const double sign : {1.0, -1.0})
        if (const double t = time_at(at + sign * step); t < best) best = t, at += sign * step;
    return {best, at};
  }

  json best_directions(const Zones& z) const {
    json j{{"zones", z.count()}};
    double total = 0;
    for (int k = 0; k < z.count(); ++k) {
      const auto [t, at] = best_direction(cells_of(z, k));
      total += t;
      j["zone_times_s"].push_back(t);
      j["zone_azimuths_deg"].push_back(at);
    }
    j["time_s"] = total;
    return j;
  }

  // Each zone along its mean steepest slope (torus) and along its principal direction (the better of
  // torus and ball), as the seed's chapter 3 does.
  json seed_protocol(const Zones& z) const {
    json j{{"zones", z.count()}};
    double steep_t = 0, steep_l = 0, steep_passes = 0, princ_t = 0, princ_l = 0;
    for (int k = 0; k < z.count(); ++k) {
      std::vector<Eigen::Vector3d> normals, points;
      for (int q = 0; q < samples(); ++q)
        if (z.zone[static_cast<std::size_t>(q)] == k) {
          normals.push_back(problem.samples.normals[static_cast<std::size_t>(q)]);
          points.push_back(problem.samples.points[static_cast<std::size_t>(q)]);
        }
      const std::vector<int> cells = cells_of(z, k);
      const ZoneMachining steep = machine(cells, mean_steepest_azimuth(normals), torus);
      steep_t += steep.time();
      steep_l += steep.pass_length + steep.link_length;
      steep_passes += steep.pass_length;
      if (points.size() < 3) {  // a sliver: no plane, no principal direction; counted along its steepest slope
        princ_t += steep.time();
        princ_l += steep.pass_length + steep.link_length;
        continue;
      }
      const PcaPlane plane = pca_plane(points);
      j["lambda_ratios"].push_back(plane.lambda(0) / plane.lambda(1));
      const ZoneMachining t = machine(cells, plane.principal_azimuth, torus), b = machine(cells, plane.principal_azimuth, ball);
      const ZoneMachining& better = t.time() < b.time() ? t : b;
      princ_t += better.time();
      princ_l += better.pass_length + better.link_length;
    }
    j["steepest"] = {{"time_s", steep_t}, {"length_mm", steep_l}, {"pass_length_mm", steep_passes}};
    j["principal"] = {{"time_s", princ_t}, {"length_mm", princ_l}};
    return j;
  }

  std::vector<int> kmeans_labels(const Eigen::Vector4d& w, int k) const {
    ClusteringSettings cs;
    cs.weights = w;
    return kmeans(problem.samples, problem.surface, k, cs);
  }
};

void emit(json j) { std::cout << j.dump() << std::endl; }

int best_directions_grid(const Scan& scan, int clusters, int levels) {
  std::set<std::vector<int>> seen;
  double best = std::numeric_limits<double>::infinity();
  for (int a = 0; a < levels; ++a)
    for (int b = 0; b < levels; ++b)
      for (int c = 0; c < levels; ++c)
        for (int d = 0; d < levels; ++d) {
          const Eigen::Vector4d w = Eigen::Vector4d(a, b, c, d) / (levels - 1);
          if (w.sum() == 0) continue;
          const Zones z = scan.zones(scan.kmeans_labels(w, clusters));
          if (!seen.insert(z.zone).second) continue;
          json j = scan.best_directions(z);
          best = std::min(best, j["time_s"].get<double>());
          j["omega"] = {w(0), w(1), w(2), w(3)};
          j["distinct"] = seen.size();
          j["best_so_far_s"] = best;
          emit(j);
        }
  return 0;
}

int shapes(const Scan& scan) {
  const int n = scan.samples();
  const char* names[] = {"u", "v", "s", "theta"};
  for (int k = 1; k <= 5; ++k)
    for (int f = 0; f < 4; ++f) {
      std::vector<double> sorted(static_cast<std::size_t>(n));
      for (int i = 0; i < n; ++i) sorted[static_cast<std::size_t>(i)] = scan.feature(i)(f);
      std::sort(sorted.begin(), sorted.end());
      std::vector<int> labels(static_cast<std::size_t>(n));
      for (int i = 0; i < n; ++i) {
        int q = 0;
        while (q < k - 1 && scan.feature(i)(f) > sorted[static_cast<std::size_t>((q + 1) * n / k)]) ++q;
        labels[static_cast<std::size_t>(i)] = q;
      }
      json j = scan.best_directions(scan.zones(labels));
      j["strips_by"] = names[f];
      j["k"] = k;
      emit(j);
    }
  for (int deg = 20; deg <= 50; deg += 5) {
    std::vector<int> labels(static_cast<std::size_t>(n));
    for (int i = 0; i < n; ++i) labels[static_cast<std::size_t>(i)] = scan.feature(i)(2) > deg * kDeg ? 1 : 0;
    json j = scan.best_directions(scan.zones(labels));
    j["split_at_slope_deg"] = deg;
    emit(j);
  }
  return 0;
}

int weights(const Scan& scan) {
  const double wide[] = {0, 0.01, 0.1, 0.3, 1, 3, 10, 30, 100, 1000, 3283};
  std::set<std::vector<int>> seen;
  for (const double wu : {0.0, 0.3, 1.0})
    for (const double wv : {0.0, 0.3, 1.0})
      for (const double ws : wide)
        for (const double wt : wide) {
          const Eigen::Vector4d w(wu, wv, ws, wt);
          if (w.sum() == 0) continue;
          const Zones z = scan.zones(scan.kmeans_labels(w, 3));
          if (!seen.insert(z.zone).second) continue;
          json j = scan.seed_protocol(z);
          j["omega"] = {wu, wv, ws, wt};
          emit(j);
        }
  return 0;
}

int seed_protocol(const Scan& scan) {
  const double range[] = {0.1, 0.3, 1, 3, 10, 30, 100};
  for (const double ws : range)
    for (const double wt : range) {
      const Eigen::Vector4d w(1, 1, ws, wt);
      for (const bool use_ward : {false, true}) {
        const Zones z = scan.zones(use_ward ? ward(scan.problem.samples, 3, w) : scan.kmeans_labels(w, 3));
        json j = scan.seed_protocol(z);
        j["method"] = use_ward ? "ward" : "kmeans";
        j["omega"] = {1, 1, ws, wt};
        emit(j);
      }
    }
  return 0;
}

int usage() {
  std::cerr << "usage: zoning_scan best-directions rubio|choi K LEVELS | shapes rubio|choi | weights rubio|choi | seed-protocol rubio|choi\n";
  return 2;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 3) return usage();
  const std::string mode = argv[1], surface = argv[2];
  if (surface != "rubio" && surface != "choi") return usage();
  const Scan scan(surface == "rubio");
  if (mode == "best-directions" && argc == 5) return best_directions_grid(scan, std::stoi(argv[3]), std::stoi(argv[4]));
  if (mode == "shapes") return shapes(scan);
  if (mode == "weights") return weights(scan);
  if (mode == "seed-protocol") return seed_protocol(scan);
  return usage();
}
