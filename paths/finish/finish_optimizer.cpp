#include "paths/finish/finish_optimizer.hpp"

#include "paths/finish/mads.hpp"
#include "paths/finish/plane_model.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <unordered_map>

namespace drom::paths {

namespace {

constexpr double kPi = std::numbers::pi;
constexpr double kDeg = kPi / 180;
constexpr double kPartitionCost = 0.2, kSurrogateShare = 0.05;

double wrap_azimuth(double a) { return reduce_azimuth(a); }

// A zone's samples' covariance, so its PCA plane can be had in any orientation.
struct ZoneStats {
  std::vector<int> samples, cells;
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Matrix3d covariance = Eigen::Matrix3d::Zero();
  PcaPlane plane;  // part frame
  double steepest = 0;
  double share = 0;  // of the surface's mesh cells
  PcaPlane rotated(const Eigen::Matrix3d& r) const { return pca_plane(r * covariance * r.transpose(), r * mean, static_cast<int>(samples.size())); }
};

struct ZoneResult {
  ZoneSetup setup;
  double time = std::numeric_limits<double>::infinity();
  Eigen::Vector3d start = Eigen::Vector3d::Zero(), end = Eigen::Vector3d::Zero();
};

std::uint64_t zone_key(const std::vector<int>& samples) {
  std::uint64_t h = 1469598103934665603ull;
  for (const int s : samples) h = (h ^ static_cast<std::uint64_t>(s)) * 1099511628211ull;
  return h ^ samples.size();
}

// Greedy nearest-next-start order of zones from their ends, and the moves' time (machine accounting).
double moves_between(const std::vector<ZoneResult>& zones, const FinishingSettings& s) {
  if (s.accounting == Accounting::seed || zones.size() < 2) return 0;
  std::vector<bool> used(zones.size(), false);
  used[0] = true;
  Eigen::Vector3d here = zones[0].end;
  double t = 0;
  for (std::size_t step = 1; step < zones.size(); ++step) {
    double best = std::numeric_limits<double>::infinity();
    std::size_t pick = 0;
    bool reverse = false;
    for (std::size_t k = 0; k < zones.size(); ++k) {
      if (used[k]) continue;
      const double f = (zones[k].start - here).norm(), b = (zones[k].end - here).norm();
      if (f < best) best = f, pick = k, reverse = false;
      if (b < best) best = b, pick = k, reverse = true;
    }
    used[pick] = true;
    const Eigen::Vector3d next = reverse ? zones[pick].end : zones[pick].start;
    t += s.timer.repositioning(here, next, std::max(here.z(), next.z()) + s.clearance, s.approach);
    here = reverse ? zones[pick].start : zones[pick].end;
  }
  return t;
}

class Search {
 public:
  Search(const FinishingProblem& p, const OptimizerSettings& o) : p_(p), o_(o) {
    total_cells_ = 0;
    for (const int s : p.mesh.sample_cell) total_cells_ += s >= 0 ? 1 : 0;
  }

  double spent() const { return spent_; }
  void charge(double cost) { spent_ += cost; }

  std::vector<ZoneStats> zone_stats(const Zones& zones) const {
    std::vector<ZoneStats> stats(static_cast<std::size_t>(zones.count()));
    for (int i = 0; i < p_.samples.size(); ++i)
      if (zones.zone[static_cast<std::size_t>(i)] >= 0) stats[static_cast<std::size_t>(zones.zone[static_cast<std::size_t>(i)])].samples.push_back(i);
    for (int c = 0; c < p_.mesh.cell_count(); ++c) {
      const int s = p_.mesh.sample_cell[static_cast<std::size_t>(c)];
      if (s >= 0 && zones.zone[static_cast<std::size_t>(s)] >= 0) stats[static_cast<std::size_t>(zones.zone[static_cast<std::size_t>(s)])].cells.push_back(c);
    }
    for (auto& z : stats) {
      std::vector<Eigen::Vector3d> points, normals;
      for (const int i : z.samples) {
        points.push_back(p_.samples.points[static_cast<std::size_t>(i)]);
        normals.push_back(p_.samples.normals[static_cast<std::size_t>(i)]);
      }
      for (const auto& q : points) z.mean += q;
      z.mean /= static_cast<double>(std::max<std::size_t>(1, points.size()));
      for (const auto& q : points) z.covariance += (q - z.mean) * (q - z.mean).transpose();
      z.covariance /= static_cast<double>(std::max<std::size_t>(1, points.size()));
      z.plane = pca_plane(z.covariance, z.mean, static_cast<int>(points.size()));
      z.steepest = mean_steepest_azimuth(normals);
      z.share = static_cast<double>(z.cells.size()) / std::max(1, total_cells_);
    }
    return stats;
  }

  // The black box on one zone; infinite where the setup leaves part of the zone out of the tool's
  // reach, or (except at the seed's start point, which is reported as it is) where the tool gouges:
  // somewhere the ground across the passes is more concave than the tool's trace (the torus's flat
  // bottom laid on a concave zone).
  ZoneResult run(const ZoneStats& z, const ZoneSetup& setup, bool start = false) {
    ZoneResult r;
    r.setup = setup;
    if (!accessible(p_.samples, z.samples, setup.axis())) return r;
    charge(z.share);
    const ZoneMachining m = machine_zone(p_.mesh, z.cells, 0, setup, p_.settings);
    if (!start && m.gouging_contacts() > 0) return r;
    if (m.passes.empty()) {
      r.time = 0;
      return r;
    }
    r.time = m.time();
    r.start = m.start();
    r.end = m.end();
    return r;
  }

  double s3(const ZoneStats& z, const Eigen::Matrix3d& rotation, double azimuth) {
    charge(kSurrogateShare * z.share);
    const PcaPlane plane = rotation.isIdentity() ? z.plane : z.rotated(rotation);
    return pca_plane_time(plane, azimuth, p_.settings.tool, p_.settings.scallop, p_.settings.timer.cutting());
  }

  // Pattern search on the azimuth alone (periodic in pi), from the best of the candidates.
  ZoneResult refine_azimuth(const ZoneStats& z, ZoneResult best, const std::function<ZoneSetup(double)>& setup_at) {
    for (double step = 8 * kDeg; step >= 0.5 * kDeg;) {
      bool moved = false;
      for (const double sign : {1.0, -1.0}) {
        const ZoneResult r = run(z, setup_at(wrap_azimuth(best.setup.azimuth + sign * step)));
        if (r.time < best.time - 1e-9) {
          best = r;
          moved = true;
          break;
        }
      }
      if (!moved) step /= 2;
    }
    return best;
  }

  double best_s3_azimuth(const ZoneStats& z, const Eigen::Matrix3d& rotation) {
    double best = std::numeric_limits<double>::infinity(), azimuth = 0;
    for (int a = -90; a < 90; a += 5) {
      const double t = s3(z, rotation, a * kDeg);
      if (t < best) best = t, azimuth = a * kDeg;
    }
    return azimuth;
  }

  ZoneResult three_axis(const ZoneStats& z) {
    std::vector<double> candidates = {z.steepest, z.plane.principal_azimuth};
    if (o_.surrogate) candidates.push_back(best_s3_azimuth(z, Eigen::Matrix3d::Identity()));
    ZoneResult best;
    for (const double a : candidates) {
      const ZoneResult r = run(z, three_axis_setup(a));
      if (r.time < best.time) best = r;
    }
    return refine_azimuth(z, best, [](double a) { return three_axis_setup(a); });
  }

  ZoneResult heuristic(const ZoneStats& z) {
    // Start: zeta = 0, along the turned zone's steepest slope (the seed's start); candidates from S3
    // over zeta and Theta; then a pattern search on (zeta, Theta).
    const auto setup_at = [&](double zeta, double azimuth) { return heuristic_setup(z.plane, zeta, azimuth); };
    const ZoneSetup flat = setup_at(0, 0);
    const double start_azimuth = machine_steepest_azimuth(p_.samples, z.samples, flat.rotation);
    ZoneResult best = run(z, setup_at(0, start_azimuth));
    if (o_.surrogate) {
      double best_t = std::numeric_limits<double>::infinity(), bz = 0, ba = 0;
      for (int zeta = -60; zeta <= 60; zeta += 5)
        for (int a = -90; a < 90; a += 10) {
          const ZoneSetup s = setup_at(zeta * kDeg, a * kDeg);
          if (!accessible(p_.samples, z.samples, s.axis())) continue;
          const double t = s3(z, s.rotation, a * kDeg);
          if (t < best_t) best_t = t, bz = zeta * kDeg, ba = a * kDeg;
        }
      const ZoneResult r = run(z, setup_at(bz, ba));
      if (r.time < best.time) best = r;
      // The principal direction of the turned zone, at the S3 zeta.
      const ZoneSetup s = setup_at(bz, 0);
      const PcaPlane turned = z.rotated(s.rotation);
      const ZoneResult q = run(z, setup_at(bz, turned.principal_azimuth));
      if (q.time < best.time) best = q;
    }
    return pattern_2d(z, best, setup_at, best.setup.zeta);
  }

  ZoneResult tilted(const ZoneStats& z, const ZoneResult& flat_best) {
    // Candidates: the 3-axis optimum, and the heuristic's turned zone expressed as a tool axis.
    ZoneResult best = flat_best;
    const ZoneResult h = heuristic(z);
    if (h.time < best.time) {
      // The same turn as a tool axis (a turn about the machine's Z differs only in the feed's azimuth).
      const Eigen::Vector3d axis = h.setup.axis(), feed = h.setup.feed();
      const double phi = std::acos(std::clamp(axis.z(), -1.0, 1.0)), psi = std::atan2(axis.y(), axis.x());
      const Eigen::Vector3d f = tilted_setup(phi, psi, 0, z.mean).rotation * feed;
      const ZoneResult r = run(z, tilted_setup(phi, psi, wrap_azimuth(std::atan2(f.y(), f.x())), z.mean));
      if (r.time < best.time) best = r;
    }
    // MADS on (Phi, Psi, Theta) from there.
    const Eigen::Vector3d axis = best.setup.axis();
    const double phi0 = std::acos(std::clamp(axis.z(), -1.0, 1.0)), psi0 = std::atan2(axis.y(), axis.x());
    Eigen::VectorXd x0(3), lo(3), hi(3);
    x0 << phi0, psi0, best.setup.azimuth;
    lo << 0, -kPi, -kPi / 2;
    hi << kPi / 2, kPi, kPi / 2;
    ZoneResult found = best;
    const auto evaluate = [&](const Eigen::VectorXd& x) {
      const double before = spent_;
      const ZoneResult r = run(z, tilted_setup(x(0), x(1), x(2), z.mean));
      if (r.time < found.time) found = r;
      return MadsPoint{x, r.time, spent_ - before};
    };
    std::function<double(const Eigen::VectorXd&)> rank;
    if (o_.surrogate) rank = [&](const Eigen::VectorXd& x) {
      const ZoneSetup s = tilted_setup(x(0), x(1), x(2), z.mean);
      return s3(z, s.rotation, x(2));
    };
    MadsSettings ms;
    ms.initial_step = 0.05;
    ms.minimum_step = 0.002;
    ms.budget = spent_ + 30 * z.share;
    mads_minimize(evaluate, rank, x0, lo, hi, ms);
    return found;
  }

  // Total over a partition, with each zone's own optimum (cached by its samples).
  std::pair<double, std::vector<ZoneResult>> partition_time(const Zones& zones, bool optimise) {
    const auto stats = zone_stats(zones);
    std::vector<ZoneResult> results;
    double total = 0;
    for (const auto& z : stats) {
      ZoneResult r;
      if (!optimise) {
        if (o_.mode == SetupMode::pca_heuristic) {
          const ZoneSetup flat = heuristic_setup(z.plane, 0, 0);
          r = run(z, heuristic_setup(z.plane, 0, machine_steepest_azimuth(p_.samples, z.samples, flat.rotation)), true);
        } else {
          r = run(z, three_axis_setup(z.steepest), true);
        }
      } else {
        const std::uint64_t key = zone_key(z.samples);
        const auto cached = cache_.find(key);
        if (cached != cache_.end()) {
          r = cached->second;
        } else {
          if (o_.mode == SetupMode::pca_heuristic) r = heuristic(z);
          else {
            r = three_axis(z);
            if (o_.mode == SetupMode::three_plus_two) r = tilted(z, r);
          }
          cache_.emplace(key, r);
        }
      }
      total += r.time;
      results.push_back(r);
    }
    return {total + moves_between(results, p_.settings), results};
  }

 private:
  ZoneResult pattern_2d(const ZoneStats& z, ZoneResult best, const std::function<ZoneSetup(double, double)>& setup_at, double zeta) {
    double azimuth = best.setup.azimuth;
    for (double step = 8 * kDeg; step >= 0.5 * kDeg;) {
      bool moved = false;
      const double moves[4][2] = {{step, 0}, {-step, 0}, {0, step}, {0, -step}};
      for (const auto& m : moves) {
        const double nz = std::clamp(zeta + m[0], -kPi / 2, kPi / 2), na = wrap_azimuth(azimuth + m[1]);
        const ZoneResult r = run(z, setup_at(nz, na));
        if (r.time < best.time - 1e-9) {
          best = r;
          zeta = nz;
          azimuth = na;
          moved = true;
          break;
        }
      }
      if (!moved) step /= 2;
    }
    return best;
  }

  const FinishingProblem& p_;
  OptimizerSettings o_;
  int total_cells_ = 0;
  double spent_ = 0;
  std::unordered_map<std::uint64_t, ZoneResult> cache_;
};

}  // namespace

FinishingProblem make_problem(const geometry::NurbsSurface& surface, const geometry::TrimLoops& trim, const FinishingSettings& settings, int sample_cells,
                              double mesh_step) {
  return FinishingProblem{surface, trim, sample_surface(surface, trim, sample_cells, sample_cells),
                          build_machining_mesh(surface, trim, mesh_step, sample_cells, sample_cells), settings};
}

ZoneSetup three_axis_setup(double azimuth) {
  ZoneSetup s;
  s.azimuth = azimuth;
  return s;
}

ZoneSetup tilted_setup(double phi, double psi, double azimuth, const Eigen::Vector3d& centre) {
  ZoneSetup s;
  const Eigen::Vector3d axis(std::sin(phi) * std::cos(psi), std::sin(phi) * std::sin(psi), std::cos(phi));
  s.rotation = Eigen::Quaterniond::FromTwoVectors(axis, Eigen::Vector3d::UnitZ()).toRotationMatrix();
  s.centre = centre;
  s.azimuth = azimuth;
  return s;
}

ZoneSetup heuristic_setup(const PcaPlane& plane, double zeta, double azimuth) {
  ZoneSetup s;
  const Eigen::Matrix3d flatten = Eigen::Quaterniond::FromTwoVectors(plane.axes.col(2), Eigen::Vector3d::UnitZ()).toRotationMatrix();
  const Eigen::Vector3d x2 = flatten * plane.axes.col(1);
  s.rotation = Eigen::AngleAxisd(zeta, x2).toRotationMatrix() * flatten;
  s.centre = plane.mean;
  s.azimuth = azimuth;
  s.zeta = zeta;
  return s;
}

bool accessible(const SurfaceSamples& samples, const std::vector<int>& zone_samples, const Eigen::Vector3d& axis) {
  for (const int i : zone_samples)
    if (samples.normals[static_cast<std::size_t>(i)].dot(axis) < 0) return false;
  return true;
}

double machine_steepest_azimuth(const SurfaceSamples& samples, const std::vector<int>& zone_samples, const Eigen::Matrix3d& rotation) {
  std::vector<Eigen::Vector3d> normals;
  for (const int i : zone_samples) normals.push_back(rotation * samples.normals[static_cast<std::size_t>(i)]);
  return mean_steepest_azimuth(normals);
}

double finishing_time(const FinishingProblem& problem, const Zones& zones, const std::vector<ZoneSetup>& setups) {
  return plan_finishing(problem.mesh, zones, setups, problem.settings).time();
}

KOptimum optimize_clusters(const FinishingProblem& problem, int clusters, const OptimizerSettings& settings) {
  KOptimum k;
  k.clusters = clusters;
  Search search(problem, settings);
  const auto partition = [&](const Eigen::Vector4d& weights) {
    ClusteringSettings cs;
    cs.weights = weights;
    search.charge(kPartitionCost);
    return connected_zones(kmeans(problem.samples, problem.surface, clusters, cs), problem.samples.cells_u, problem.samples.cells_v);
  };
  {
    const Zones zones = partition(Eigen::Vector4d::Ones());
    k.start_time = search.partition_time(zones, false).first;
  }
  k.history.emplace_back(search.spent(), k.start_time);
  double best = std::numeric_limits<double>::infinity();
  const auto evaluate = [&](const Eigen::VectorXd& w) {
    const double before = search.spent();
    const Zones zones = partition(w);
    auto [t, results] = search.partition_time(zones, true);
    ++k.evaluations;
    if (t < best) {
      best = t;
      k.weights = w;
      k.zones = zones;
      k.setups.clear();
      for (const auto& r : results) k.setups.push_back(r.setup);
    }
    k.history.emplace_back(search.spent(), std::min(best, k.start_time));
    return MadsPoint{w, t, search.spent() - before};
  };
  std::function<double(const Eigen::VectorXd&)> rank;
  if (settings.surrogate) rank = [&](const Eigen::VectorXd& w) {
    const Zones zones = partition(w);
    double t = 0;
    for (const auto& z : search.zone_stats(zones)) {
      double b = std::numeric_limits<double>::infinity();
      for (int a = -90; a < 90; a += 15) b = std::min(b, search.s3(z, Eigen::Matrix3d::Identity(), a * kDeg));
      t += b;
    }
    return t;
  };
  // A search step before the poll (NOMAD has one too): the seed's start and the partitions by one
  // or two features alone; the poll starts from the best of them.
  Eigen::VectorXd start = Eigen::Vector4d::Ones();
  double start_value = std::numeric_limits<double>::infinity();
  const Eigen::Vector4d probes[] = {Eigen::Vector4d::Ones(),      Eigen::Vector4d(1, 0, 0, 0), Eigen::Vector4d(0, 1, 0, 0), Eigen::Vector4d(0, 0, 1, 0),
                                    Eigen::Vector4d(0, 0, 0, 1), Eigen::Vector4d(1, 1, 0, 0), Eigen::Vector4d(0, 0, 1, 1)};
  for (const auto& w : probes) {
    if (search.spent() >= settings.budget) break;
    const MadsPoint p = evaluate(w);
    if (p.value < start_value) start_value = p.value, start = w;
  }
  MadsSettings ms;
  ms.budget = settings.budget - search.spent();
  ms.initial_step = 0.25;
  ms.minimum_step = 1.0 / 64;
  if (ms.budget > 0) mads_minimize(evaluate, rank, start, Eigen::Vector4d::Zero(), Eigen::Vector4d::Ones(), ms);
  k.best_time = std::min(best, k.start_time);
  if (!(best <= k.start_time)) {
    // Nothing beat the start (cannot happen unless the budget ran out first): keep the start.
    k.zones = partition(Eigen::Vector4d::Ones());
    k.setups.clear();
    for (const auto& z : search.zone_stats(k.zones)) k.setups.push_back(three_axis_setup(z.steepest));
  }
  k.spent = search.spent();
  return k;
}

}  // namespace drom::paths
