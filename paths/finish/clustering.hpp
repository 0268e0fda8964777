#pragma once
// Partitioning a surface's samples into zones (Herraz ch. 3): K-means, rival-penalized competitive
// learning (RPCL) and Ward's hierarchical clustering on the features (u, v, s, theta), under the
// Euclidean, Mahalanobis, standard-deviation, weighted (ch. 4) and PCA metrics; then every connected
// piece of a cluster becomes a zone of its own. Labels are per sample, -1 for samples not machined.
#include "geometry/nurbs_surface.hpp"
#include "paths/finish/surface_samples.hpp"

#include <cstdint>
#include <vector>

namespace drom::paths {

enum class Metric {
  euclidean,    // sum of (x_j - c_j)^2, times the weights omega_j (1 by default; ch. 4 optimises them)
  mahalanobis,  // (x - c)' Sigma^-1 (x - c), Sigma the features' covariance over the surface
  std_dev,      // sum of (x_j - c_j)^2 / sigma_j, as printed in §3.5.3 (sigma, not sigma^2)
  pca,          // Euclidean plus f(lambda_II / lambda_I) [sin^2(theta_I - beta) + sin^2(theta_bar - theta_I')] (eq. 3.2)
};
enum class PcaWeight {
  ratio_squared,            // f = (lambda_II / lambda_I)^2
  one_minus_ratio_squared,  // f = 1 - (lambda_II / lambda_I)^2
};

struct ClusteringSettings {
  Metric metric = Metric::euclidean;
  Eigen::Vector4d weights = Eigen::Vector4d::Ones();  // omega, on the Euclidean metric
  PcaWeight pca_weight = PcaWeight::one_minus_ratio_squared;
  int max_iterations = 300;
};

// K-means from the seed's circle of initial centroids (eq. 3.4); centroids are exact means. Under the
// PCA metric each zone's point covariance follows every move (running covariances).
std::vector<int> kmeans(const SurfaceSamples& samples, const geometry::NurbsSurface& surface, int clusters, const ClusteringSettings& settings);

struct RpclSettings {
  double winner_rate = 0.05, rival_rate = 0.005;  // alpha_c, alpha_r at the start; both decay as 1 / (1 + t / n)
  double rate_tolerance = 1e-4;    // stop when both rates fall below
  double changed_fraction = 0.01;  // or when an assignment sweep moves fewer samples than this share
  std::uint64_t seed = 1;
};
// RPCL (Alg. 2) with the seed's extra assignment step (so global metrics such as the PCA metric
// apply); clusters may vanish, so fewer than `clusters` labels can come back.
std::vector<int> rpcl(const SurfaceSamples& samples, const geometry::NurbsSurface& surface, int clusters, const ClusteringSettings& settings,
                      const RpclSettings& rpcl);

// Ward's hierarchical clustering (Alg. 3) on the weighted Euclidean features, cut at `clusters`
// (nearest-neighbour chain, O(n^2) time, O(n) memory). With clusters = 0 the cut is before the
// largest jump between successive merge distances, among 2..max_clusters clusters.
std::vector<int> ward(const SurfaceSamples& samples, int clusters, const Eigen::Vector4d& weights = Eigen::Vector4d::Ones(), int max_clusters = 10);

struct Zones {
  std::vector<int> zone;     // per sample, -1 where not machined
  std::vector<int> cluster;  // per zone: the cluster it is a connected piece of
  int count() const { return static_cast<int>(cluster.size()); }
};
// Connected pieces (4-neighbours on the sample grid) of each cluster, numbered in scan order; an
// explicit stack, so no recursion depth limit (the seed's Alg. 4 recurses).
Zones connected_zones(const std::vector<int>& labels, int cells_u, int cells_v);

}  // namespace drom::paths
