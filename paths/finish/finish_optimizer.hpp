#pragma once
// The seed's optimisation (Herraz ch. 4): for each number of clusters K, the feature weights omega
// (K-means, weighted Euclidean metric) and every zone's feed direction Theta, and for 3+2 machining
// every zone's orientation, chosen to finish the surface in the least time. Also the seed's 3+2 PCA
// heuristic (§4.5): each zone turned flat about X_III x Z, then tilted by zeta about X_II.
//
// The seed runs NOMAD on all variables at once. Here the structure is used: a zone's time depends
// only on its own direction and orientation, so a mesh adaptive direct search (mads.hpp) over omega
// partitions the surface, and each zone's setup is optimised on its own, starting from the seed's
// start point, its principal direction, the PCA heuristic and the best direction the analytic
// surrogate S3 (Annex E) finds, then refined by pattern search. Zone results are cached by the set of
// samples, so a partition seen again costs nothing. The budget counts black-box equivalents: a zone
// evaluation costs its share of the surface's mesh cells, a partition 0.2, an S3 evaluation 5 % of
// the zone's (the seed's measured surrogate cost ratios are 1.2-5.4 %).
// A setup that undercuts the zone (eq. 4.1) or, past the seed's start point, gouges it (the curved
// model's step is 0 somewhere: the ground across the pass more concave than the tool's trace) is
// infeasible.
#include "paths/finish/clustering.hpp"
#include "paths/finish/finishing_plan.hpp"
#include "paths/finish/machining_mesh.hpp"
#include "paths/finish/surface_samples.hpp"
#include "paths/finish/zone_machining.hpp"

#include <functional>
#include <map>
#include <memory>
#include <vector>

namespace drom::paths {

enum class SetupMode {
  three_axis,    // Theta per zone
  three_plus_two,  // Theta, and the tool axis (Phi from Z, Psi its azimuth) per zone
  pca_heuristic,   // Theta and zeta per zone, the zone turned by the PCA heuristic
};

// Everything an evaluation needs, built once per surface.
struct FinishingProblem {
  geometry::NurbsSurface surface;
  geometry::TrimLoops trim;
  SurfaceSamples samples;  // the clustering grid
  MachiningMesh mesh;
  FinishingSettings settings;
};
FinishingProblem make_problem(const geometry::NurbsSurface& surface, const geometry::TrimLoops& trim, const FinishingSettings& settings, int sample_cells,
                              double mesh_step);

// Zone setups. `centre` is the point the part turns about (the zone's mean).
ZoneSetup three_axis_setup(double azimuth);
ZoneSetup tilted_setup(double phi, double psi, double azimuth, const Eigen::Vector3d& centre);
ZoneSetup heuristic_setup(const PcaPlane& zone_plane, double zeta, double azimuth);
// Whether every sample of the zone faces the tool (n . axis >= 0: no undercut, seed eq. 4.1).
bool accessible(const SurfaceSamples& samples, const std::vector<int>& zone_samples, const Eigen::Vector3d& axis);
// The steepest azimuth of the zone's normals seen in the setup's machine frame.
double machine_steepest_azimuth(const SurfaceSamples& samples, const std::vector<int>& zone_samples, const Eigen::Matrix3d& rotation);

struct OptimizerSettings {
  SetupMode mode = SetupMode::three_axis;
  double budget = 1000;   // black-box equivalents per K
  bool surrogate = true;  // S3 ranks polls and proposes zone directions
};

struct KOptimum {
  int clusters = 0;
  double start_time = 0;  // f0: omega = 1, each zone along its steepest direction (flat, for 3+2 and 3-axis; zeta = 0 for the heuristic)
  double best_time = 0;   // f*
  Eigen::Vector4d weights = Eigen::Vector4d::Ones();
  Zones zones;
  std::vector<ZoneSetup> setups;  // one per zone
  double spent = 0;               // black-box equivalents
  int evaluations = 0;            // partitions evaluated
  std::vector<std::pair<double, double>> history;  // (black-box equivalents, best time)
  double gain() const { return start_time > 0 ? (start_time - best_time) / start_time : 0; }
};

// One K: the seed's start point, then the search. Deterministic.
KOptimum optimize_clusters(const FinishingProblem& problem, int clusters, const OptimizerSettings& settings);

// The time of a given partition and setups, as the black box computes it.
double finishing_time(const FinishingProblem& problem, const Zones& zones, const std::vector<ZoneSetup>& setups);

}  // namespace drom::paths
