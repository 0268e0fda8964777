#pragma once
// The repulsive field precomputed on a voxel grid (seed 000 ch. 4): the F1 force F(x) = Σ_i F_i(x) (4.2)
// stored at the grid's corners in an OpenVDB grid, sparse: a corner is kept only where an obstacle lies
// within r0 of the voxels around it (the seed's pruning rule 4.3), and corners deep on the material
// side of their nearest obstacle (n_out · (P − O) < 0 by more than a voxel diagonal) are dropped (the
// seed's normal-sign rule): the tool never goes there, and the voxels straddling the surface keep the
// values a query just outside needs. Queried trilinearly (4.4), triquadratically (OpenVDB's
// QuadraticSampler, 27 corners), or tricubically (Catmull-Rom, 64 corners: the seed's "cubic").
// Each corner also stores its nearest obstacle distance (one 4-vector per corner, read in one pass).
//
// Beyond the seed, the near field: within `near_field` voxels of an obstacle the exact sum replaces
// the grid (blended over the outer half of that band, so the force stays continuous). The Khatib force
// grows like 1/r³; a corner that happens to lie 0.05 mm from an obstacle holds 10⁶ N, which
// interpolation spreads over its whole voxel: 1 mm from an impeller blade, 1 mm voxels, the grid alone
// is off by 920 % on average and 59 000 % at worst (OrientVoxelField.TheNearFieldIsExact...), so the
// barrier that keeps a node out of a wall is the grid's accident there, not the model's.
#include "paths/orient/axis_dynamics.hpp"
#include "paths/orient/repulsive_field.hpp"

#include <memory>

namespace drom::paths {

enum class VoxelInterpolation { trilinear, triquadratic, tricubic };
const char* interpolation_name(VoxelInterpolation i);

struct VoxelFieldSettings {
  double voxel = 1;  // L_v, mm (the seed's 2, 1, 0.5)
  VoxelInterpolation interpolation = VoxelInterpolation::trilinear;
  bool prune_material_side = true;
  double near_field = 3;  // voxels: the exact sum within this distance of an obstacle; 0: the seed's grid alone
};

class VoxelField : public ForceField {
 public:
  // `obstacles` must outlive the field when the near field is on (it sums them there).
  VoxelField(const ObstacleCloud& obstacles, const KhatibParameters& khatib, const VoxelFieldSettings& settings);
  VoxelField(ObstacleCloud&& obstacles, const KhatibParameters& khatib, const VoxelFieldSettings& settings) = delete;
  ~VoxelField() override;
  FieldSample sample(const Eigen::Vector3d& p) const override;
  Eigen::Vector3d force(const Eigen::Vector3d& p) const override;
  std::size_t stored_corners() const;
  std::size_t pruned_material_corners() const { return pruned_material_; }
  std::size_t memory_bytes() const;

 private:
  struct Impl;
  Eigen::Vector3d grid_force(const Eigen::Vector3d& p, double* nearest) const;
  Eigen::Vector3d near_corrected(const Eigen::Vector3d& p, const Eigen::Vector3d& grid, double nearest) const;
  std::unique_ptr<Impl> impl_;
  std::size_t pruned_material_ = 0;
};

}  // namespace drom::paths
