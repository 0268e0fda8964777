#include "paths/finish/clustering.hpp"

#include "geometry/local_geometry.hpp"
#include "paths/finish/running_covariance.hpp"

#include <Eigen/Dense>
#include <Eigen/Eigenvalues>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <random>
#include <stdexcept>

namespace drom::paths {

namespace {

using Vec4 = Eigen::Vector4d;

// The part of a metric between a sample and a centroid: M-weighted squared difference, M diagonal
// except for Mahalanobis.
class PointMetric {
 public:
  PointMetric(const SurfaceSamples& s, const ClusteringSettings& settings) {
    if (settings.metric == Metric::euclidean || settings.metric == Metric::pca) {
      diagonal_ = settings.weights;
      return;
    }
    Vec4 mean = Vec4::Zero();
    int n = 0;
    for (int k = 0; k < s.size(); ++k)
      if (s.inside[static_cast<std::size_t>(k)]) mean += s.features[static_cast<std::size_t>(k)], ++n;
    mean /= n;
    Eigen::Matrix4d cov = Eigen::Matrix4d::Zero();
    for (int k = 0; k < s.size(); ++k)
      if (s.inside[static_cast<std::size_t>(k)]) {
        const Vec4 d = s.features[static_cast<std::size_t>(k)] - mean;
        cov += d * d.transpose();
      }
    cov /= n;
    if (settings.metric == Metric::std_dev) {
      for (int j = 0; j < 4; ++j) diagonal_(j) = cov(j, j) > 0 ? 1 / std::sqrt(cov(j, j)) : 0;
    } else {
      full_ = true;
      inverse_ = cov.completeOrthogonalDecomposition().pseudoInverse();
    }
  }
  double operator()(const Vec4& x, const Vec4& c) const {
    const Vec4 d = x - c;
    return full_ ? d.dot(inverse_ * d) : d.cwiseProduct(d).dot(diagonal_);
  }

 private:
  bool full_ = false;
  Vec4 diagonal_ = Vec4::Ones();
  Eigen::Matrix4d inverse_ = Eigen::Matrix4d::Identity();
};

// A zone's shape for the PCA metric: its points' running covariance, principal azimuth theta_I and
// eigenvalue ratio, and its centre S(u_bar, v_bar).
struct ClusterShape {
  RunningCovariance<3> points;
  double principal = 0, weight = 0;
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
};

double principal_azimuth(const Eigen::Matrix3d& covariance, double* ratio) {
  Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> e;
  e.computeDirect(covariance);
  const Eigen::Vector3d x1 = e.eigenvectors().col(2);
  if (ratio) *ratio = e.eigenvalues()(2) > 0 ? std::max(0.0, e.eigenvalues()(1)) / e.eigenvalues()(2) : 1.0;
  return std::atan2(x1.y(), x1.x());
}

class Partitioner {
 public:
  Partitioner(const SurfaceSamples& s, const geometry::NurbsSurface& surface, int clusters, const ClusteringSettings& settings)
      : s_(s), surface_(surface), settings_(settings), metric_(s, settings), pca_(settings.metric == Metric::pca), centroids_(static_cast<std::size_t>(clusters)) {
    if (clusters < 1) throw std::invalid_argument("clustering needs at least one cluster");
    constexpr double pi = std::numbers::pi;
    // The seed's start (eq. 3.4): centroids on a circle of radius 1/4 around the domain's centre,
    // with the slope and azimuth of the surface there.
    for (int k = 1; k <= clusters; ++k) {
      const double u = 0.5 + 0.25 * std::cos(2 * k * pi / clusters), v = 0.5 + 0.25 * std::sin(2 * k * pi / clusters);
      const auto d = surface.derivatives(surface.u_min() + u * (surface.u_max() - surface.u_min()), surface.v_min() + v * (surface.v_max() - surface.v_min()));
      Eigen::Vector3d n = d.du.cross(d.dv).normalized();
      if (n.z() < 0) n = -n;
      centroids_[static_cast<std::size_t>(k - 1)] = Vec4(u, v, geometry::slope(n, Eigen::Vector3d::UnitZ()), geometry::steepest_azimuth(n));
    }
    labels_.assign(static_cast<std::size_t>(s.size()), -1);
  }

  const std::vector<int>& labels() const { return labels_; }
  std::vector<Vec4>& centroids() { return centroids_; }
  const PointMetric& point_metric() const { return metric_; }

  // Every sample to its nearest centroid; returns how many changed. Under the PCA metric the zones'
  // covariances follow each move as it happens.
  int assign() {
    if (pca_ && shapes_.empty()) {
      // The PCA terms need zones: start from the Euclidean part.
      assign_point_metric();
      build_shapes();
    }
    if (pca_) refresh_shapes();
    int changed = 0;
    for (int i = 0; i < s_.size(); ++i) {
      if (!s_.inside[static_cast<std::size_t>(i)]) continue;
      int best = 0;
      double best_d = std::numeric_limits<double>::infinity();
      for (int k = 0; k < static_cast<int>(centroids_.size()); ++k) {
        const double d = distance(i, k);
        if (d < best_d) best_d = d, best = k;
      }
      int& label = labels_[static_cast<std::size_t>(i)];
      if (label == best) continue;
      if (pca_) move_sample(i, label, best);
      label = best;
      ++changed;
    }
    return changed;
  }

  void update_centroids() {
    std::vector<Vec4> sum(centroids_.size(), Vec4::Zero());
    std::vector<int> count(centroids_.size(), 0);
    for (int i = 0; i < s_.size(); ++i) {
      const int l = labels_[static_cast<std::size_t>(i)];
      if (l < 0) continue;
      sum[static_cast<std::size_t>(l)] += s_.features[static_cast<std::size_t>(i)];
      ++count[static_cast<std::size_t>(l)];
    }
    for (std::size_t k = 0; k < centroids_.size(); ++k)
      if (count[k] > 0) centroids_[k] = sum[k] / count[k];
  }

 private:
  void assign_point_metric() {
    for (int i = 0; i < s_.size(); ++i) {
      if (!s_.inside[static_cast<std::size_t>(i)]) continue;
      int best = 0;
      double best_d = std::numeric_limits<double>::infinity();
      for (int k = 0; k < static_cast<int>(centroids_.size()); ++k) {
        const double d = metric_(s_.features[static_cast<std::size_t>(i)], centroids_[static_cast<std::size_t>(k)]);
        if (d < best_d) best_d = d, best = k;
      }
      labels_[static_cast<std::size_t>(i)] = best;
    }
  }

  void build_shapes() {
    shapes_.assign(centroids_.size(), ClusterShape{});
    for (int i = 0; i < s_.size(); ++i)
      if (labels_[static_cast<std::size_t>(i)] >= 0) shapes_[static_cast<std::size_t>(labels_[static_cast<std::size_t>(i)])].points.add(s_.points[static_cast<std::size_t>(i)]);
  }

  void refresh_shape(std::size_t k) {
    auto& z = shapes_[k];
    double ratio = 1;
    z.principal = z.points.count() >= 2 ? principal_azimuth(z.points.covariance(), &ratio) : 0.0;
    z.weight = settings_.pca_weight == PcaWeight::ratio_squared ? ratio * ratio : 1 - ratio * ratio;
  }

  void refresh_shapes() {
    for (std::size_t k = 0; k < shapes_.size(); ++k) {
      refresh_shape(k);
      const Vec4& c = centroids_[k];
      shapes_[k].centre = surface_.point(surface_.u_min() + c(0) * (surface_.u_max() - surface_.u_min()), surface_.v_min() + c(1) * (surface_.v_max() - surface_.v_min()));
    }
  }

  void move_sample(int i, int from, int to) {
    const Eigen::Vector3d& p = s_.points[static_cast<std::size_t>(i)];
    if (from >= 0) {
      shapes_[static_cast<std::size_t>(from)].points.remove(p);
      refresh_shape(static_cast<std::size_t>(from));
    }
    shapes_[static_cast<std::size_t>(to)].points.add(p);
    refresh_shape(static_cast<std::size_t>(to));
  }

  double distance(int i, int k) const {
    const Vec4& x = s_.features[static_cast<std::size_t>(i)];
    const Vec4& c = centroids_[static_cast<std::size_t>(k)];
    double d = metric_(x, c);
    if (!pca_) return d;
    const ClusterShape& z = shapes_[static_cast<std::size_t>(k)];
    const Eigen::Vector3d& p = s_.points[static_cast<std::size_t>(i)];
    const Eigen::Vector3d to_sample = p - z.centre;
    const double beta = std::atan2(to_sample.y(), to_sample.x());
    double principal_if_joined = z.principal;
    if (labels_[static_cast<std::size_t>(i)] != k) {
      RunningCovariance<3> joined = z.points;
      joined.add(p);
      principal_if_joined = principal_azimuth(joined.covariance(), nullptr);
    }
    const double a = std::sin(z.principal - beta), b = std::sin(c(3) - principal_if_joined);
    return d + z.weight * (a * a + b * b);
  }

  const SurfaceSamples& s_;
  const geometry::NurbsSurface& surface_;
  ClusteringSettings settings_;
  PointMetric metric_;
  bool pca_;
  std::vector<Vec4> centroids_;
  std::vector<int> labels_;
  std::vector<ClusterShape> shapes_;
};

// Labels renumbered 0..m-1 in order of first appearance (clusters that emptied vanish).
std::vector<int> renumber(const std::vector<int>& labels) {
  std::vector<int> map, out(labels.size(), -1);
  int next = 0;
  for (std::size_t i = 0; i < labels.size(); ++i) {
    const int l = labels[i];
    if (l < 0) continue;
    if (static_cast<std::size_t>(l) >= map.size()) map.resize(static_cast<std::size_t>(l) + 1, -1);
    if (map[static_cast<std::size_t>(l)] < 0) map[static_cast<std::size_t>(l)] = next++;
    out[i] = map[static_cast<std::size_t>(l)];
  }
  return out;
}

}  // namespace

std::vector<int> kmeans(const SurfaceSamples& samples, const geometry::NurbsSurface& surface, int clusters, const ClusteringSettings& settings) {
  Partitioner p(samples, surface, clusters, settings);
  p.assign();
  for (int it = 0; it < settings.max_iterations; ++it) {
    p.update_centroids();
    if (p.assign() == 0) break;
  }
  return p.labels();
}

std::vector<int> rpcl(const SurfaceSamples& samples, const geometry::NurbsSurface& surface, int clusters, const ClusteringSettings& settings,
                      const RpclSettings& r) {
  Partitioner p(samples, surface, clusters, settings);
  std::vector<int> inside;
  for (int i = 0; i < samples.size(); ++i)
    if (samples.inside[static_cast<std::size_t>(i)]) inside.push_back(i);
  const double n = static_cast<double>(inside.size());
  std::mt19937_64 rng(r.seed);
  std::uniform_int_distribution<std::size_t> pick(0, inside.size() - 1);
  std::vector<double> wins(static_cast<std::size_t>(clusters), 1.0);
  double total_wins = clusters;
  auto& centroids = p.centroids();
  long long t = 0;
  p.assign();
  for (int epoch = 0; epoch < settings.max_iterations; ++epoch) {
    double winner_rate = r.winner_rate, rival_rate = r.rival_rate;
    for (std::size_t draw = 0; draw < inside.size(); ++draw, ++t) {
      const Vec4& x = samples.features[static_cast<std::size_t>(inside[pick(rng)])];
      int c = -1, rival = -1;
      double dc = std::numeric_limits<double>::infinity(), dr = dc;
      for (int k = 0; k < clusters; ++k) {
        const double d = wins[static_cast<std::size_t>(k)] / total_wins * p.point_metric()(x, centroids[static_cast<std::size_t>(k)]);
        if (d < dc) {
          rival = c, dr = dc;
          c = k, dc = d;
        } else if (d < dr) {
          rival = k, dr = d;
        }
      }
      const double decay = 1 / (1 + static_cast<double>(t) / n);
      winner_rate = r.winner_rate * decay;
      rival_rate = r.rival_rate * decay;
      centroids[static_cast<std::size_t>(c)] += winner_rate * (x - centroids[static_cast<std::size_t>(c)]);
      if (rival >= 0) centroids[static_cast<std::size_t>(rival)] -= rival_rate * (x - centroids[static_cast<std::size_t>(rival)]);
      wins[static_cast<std::size_t>(c)] += 1;
      total_wins += 1;
    }
    const int changed = p.assign();
    if (changed < r.changed_fraction * n || (winner_rate < r.rate_tolerance && rival_rate < r.rate_tolerance)) break;
  }
  return renumber(p.labels());
}

std::vector<int> ward(const SurfaceSamples& samples, int clusters, const Eigen::Vector4d& weights, int max_clusters) {
  std::vector<int> ids;
  for (int i = 0; i < samples.size(); ++i)
    if (samples.inside[static_cast<std::size_t>(i)]) ids.push_back(i);
  const std::size_t n = ids.size();
  if (n == 0) return std::vector<int>(static_cast<std::size_t>(samples.size()), -1);
  const Vec4 scale = weights.cwiseSqrt();
  // Slots hold clusters (size, centroid in scaled features); `rep` is a sample of each, for the merges.
  std::vector<Vec4> centroid(n);
  std::vector<double> size(n, 1.0);
  std::vector<int> rep(n);
  for (std::size_t k = 0; k < n; ++k) {
    centroid[k] = samples.features[static_cast<std::size_t>(ids[k])].cwiseProduct(scale);
    rep[k] = static_cast<int>(k);
  }
  std::vector<int> active(n);
  std::vector<int> position(n);
  for (std::size_t k = 0; k < n; ++k) active[k] = static_cast<int>(k), position[k] = static_cast<int>(k);
  const auto deactivate = [&](int slot) {
    const int p = position[static_cast<std::size_t>(slot)], last = active.back();
    active[static_cast<std::size_t>(p)] = last;
    position[static_cast<std::size_t>(last)] = p;
    active.pop_back();
    position[static_cast<std::size_t>(slot)] = -1;
  };
  const auto distance = [&](int a, int b) {
    const double na = size[static_cast<std::size_t>(a)], nb = size[static_cast<std::size_t>(b)];
    return na * nb / (na + nb) * (centroid[static_cast<std::size_t>(a)] - centroid[static_cast<std::size_t>(b)]).squaredNorm();
  };
  struct Merge {
    int a, b;
    double height;
  };
  std::vector<Merge> merges;
  merges.reserve(n - 1);
  std::vector<int> chain;
  while (active.size() > 1) {
    if (chain.empty()) chain.push_back(active.front());
    const int a = chain.back();
    const int previous = chain.size() >= 2 ? chain[chain.size() - 2] : -1;
    int b = previous;
    double best = previous >= 0 ? distance(a, previous) : std::numeric_limits<double>::infinity();
    for (const int c : active) {
      if (c == a) continue;
      const double d = distance(a, c);
      if (d < best) best = d, b = c;
    }
    if (b == previous) {
      chain.pop_back();
      chain.pop_back();
      merges.push_back({rep[static_cast<std::size_t>(a)], rep[static_cast<std::size_t>(b)], best});
      const double na = size[static_cast<std::size_t>(a)], nb = size[static_cast<std::size_t>(b)];
      centroid[static_cast<std::size_t>(a)] = (na * centroid[static_cast<std::size_t>(a)] + nb * centroid[static_cast<std::size_t>(b)]) / (na + nb);
      size[static_cast<std::size_t>(a)] = na + nb;
      deactivate(b);
    } else {
      chain.push_back(b);
    }
  }
  std::stable_sort(merges.begin(), merges.end(), [](const Merge& x, const Merge& y) { return x.height < y.height; });
  if (clusters <= 0) {
    // Before the largest jump between successive merge heights, among 2..max_clusters clusters.
    double best_gap = -1;
    clusters = 2;
    for (int k = 2; k <= max_clusters && static_cast<std::size_t>(k) < n; ++k) {
      const double gap = merges[n - static_cast<std::size_t>(k)].height - merges[n - static_cast<std::size_t>(k) - 1].height;
      if (gap > best_gap) best_gap = gap, clusters = k;
    }
  }
  clusters = std::min<int>(clusters, static_cast<int>(n));
  std::vector<int> parent(n);
  for (std::size_t k = 0; k < n; ++k) parent[k] = static_cast<int>(k);
  const auto find = [&](int x) {
    while (parent[static_cast<std::size_t>(x)] != x) x = parent[static_cast<std::size_t>(x)] = parent[static_cast<std::size_t>(parent[static_cast<std::size_t>(x)])];
    return x;
  };
  for (std::size_t m = 0; m + static_cast<std::size_t>(clusters) < n; ++m) parent[static_cast<std::size_t>(find(merges[m].a))] = find(merges[m].b);
  std::vector<int> labels(static_cast<std::size_t>(samples.size()), -1);
  for (std::size_t k = 0; k < n; ++k) labels[static_cast<std::size_t>(ids[k])] = find(static_cast<int>(k));
  return renumber(labels);
}

Zones connected_zones(const std::vector<int>& labels, int cells_u, int cells_v) {
  Zones z;
  z.zone.assign(labels.size(), -1);
  std::vector<int> stack;
  for (int i = 0; i < cells_u; ++i)
    for (int j = 0; j < cells_v; ++j) {
      const int start = i * cells_v + j;
      const int l = labels[static_cast<std::size_t>(start)];
      if (l < 0 || z.zone[static_cast<std::size_t>(start)] >= 0) continue;
      const int id = z.count();
      z.cluster.push_back(l);
      z.zone[static_cast<std::size_t>(start)] = id;
      stack.push_back(start);
      while (!stack.empty()) {
        const int c = stack.back();
        stack.pop_back();
        const int ci = c / cells_v, cj = c % cells_v;
        const int neighbours[4][2] = {{ci - 1, cj}, {ci + 1, cj}, {ci, cj - 1}, {ci, cj + 1}};
        for (const auto& nb : neighbours) {
          if (nb[0] < 0 || nb[0] >= cells_u || nb[1] < 0 || nb[1] >= cells_v) continue;
          const int q = nb[0] * cells_v + nb[1];
          if (labels[static_cast<std::size_t>(q)] != l || z.zone[static_cast<std::size_t>(q)] >= 0) continue;
          z.zone[static_cast<std::size_t>(q)] = id;
          stack.push_back(q);
        }
      }
    }
  return z;
}

}  // namespace drom::paths
