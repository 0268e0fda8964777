#pragma once
// The proof the seed does not give: the final orientations checked against the check surfaces with
// no mesh-node luck. The check surfaces' triangles go into an OpenVDB narrow band (meshToVolume) that
// keeps, per voxel, its closest triangle; a query takes the triangles of the 8 voxels around it and
// measures the exact point-triangle distance, signed by the triangle's outward material normal where the
// point lies in front of or behind a face (beside an open border the distance is unsigned). The
// shank+holder solid is covered, slab by slab along the axis (step `axial_step`), by spheres centred on
// the axis (radius √(ρ_max² + (Δz/2)²) for the slab's largest radius ρ_max): the clearance reported is
// a lower bound of the true one, conservative by at most (Δz/2)² / (2ρ).
//
// The gouge check does the same for the cutting part: against the part surfaces (sampled at
// `gouge_spacing`; the depth of any sample inside the cutter, from its exact signed distance) and
// against the check surfaces (the cutter's solid must not reach them either).
#include "paths/orient/orient_scene.hpp"

#include <Eigen/Core>

#include <memory>
#include <string>
#include <vector>

namespace drom::paths {

class ObstacleDistance {
 public:
  // `band`: mm around the triangles where distances are exact; farther queries return +band.
  ObstacleDistance(const TriangleSoup& soup, double voxel, double band);
  ~ObstacleDistance();
  ObstacleDistance(const ObstacleDistance&) = delete;
  ObstacleDistance& operator=(const ObstacleDistance&) = delete;
  // Signed distance (mm): negative on the material side of the nearest triangle.
  double distance(const Eigen::Vector3d& p) const;
  double band() const { return band_; }
  std::size_t active_voxels() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  double band_;
};

struct ClearanceSettings {
  double voxel = 0.5;          // mm, the distance grid's voxel
  double axial_step = 0.5;     // mm between the covering spheres' centres
  double required = 0.0;       // mm: clearance below this is a violation (0: contact)
  double gouge_spacing = 0.5;  // mm between part-surface samples for the gouge check
  double gouge_tolerance = 0.005;  // mm of depth tolerated (the sampling's chord)
};

struct PoseCheck {
  double clearance = 1e300;     // shank+holder to the check surfaces (mm; negative: interpenetration)
  double clearance_height = 0;  // above the tip, where it is least
  double gouge_depth = 0;       // the cutter's deepest intrusion into a part or check surface (mm, ≥ 0)
};

struct Violation {
  std::size_t pass = 0, index = 0;
  double s = 0, value = 0;   // mm
  std::string what;
};

struct ClearanceReport {
  std::vector<std::vector<PoseCheck>> passes;   // per pass, per pose
  double worst_clearance = 1e300, worst_gouge = 0;
  std::vector<Violation> collisions, gouges;    // every one (pass, pose)
  long poses = 0;
};

class ClearanceChecker {
 public:
  ClearanceChecker(const OrientScene& scene, const ClearanceSettings& settings);
  ~ClearanceChecker();
  // One pose: CL (the pivot) and the tool axis.
  PoseCheck check(const Eigen::Vector3d& cl, const Eigen::Vector3d& axis) const;
  // Every pass's poses (cl, axis, s per pose).
  ClearanceReport check_all(const std::vector<std::vector<Eigen::Vector3d>>& cl, const std::vector<std::vector<Eigen::Vector3d>>& axes,
                            const std::vector<std::vector<double>>& s) const;
  const ObstacleDistance& distance() const { return *distance_; }

 private:
  const OrientScene& scene_;
  ClearanceSettings settings_;
  std::unique_ptr<ObstacleDistance> distance_;
  ObstacleCloud part_samples_;
  std::vector<std::pair<double, double>> slabs_;  // (centre height above the pivot, covering radius)
  double cutter_reach_ = 0;
};

}  // namespace drom::paths
