#pragma once
// The repulsive field precomputed on a voxel grid (seed 000 ch. 4): the F1 force F(x) = Σ_i F_i(x) (4.2)
// stored at the grid's corners in an OpenVDB vector grid, sparse: a corner is kept only where an
// obstacle lies within r0 of the voxels around it (the seed's pruning rule 4.3), and corners deep on
// the material side of their nearest obstacle (n_out · (P − O) < 0 by more than a voxel diagonal) are
// dropped (the seed's normal-sign rule): the tool never goes there, and the voxels straddling the surface
// keep the values a query just outside needs. Queried trilinearly (4.4), triquadratically (OpenVDB's
// QuadraticSampler, 27 corners), or tricubically (Catmull-Rom, 64 corners: the seed's "cubic").
// The nearest obstacle distance is stored beside it (for the integrator's step cap).
#include "paths/axis_dynamics.hpp"
#include "paths/repulsive_field.hpp"

#include <memory>

namespace drom::paths {

enum class VoxelInterpolation { trilinear, triquadratic, tricubic };
const char* interpolation_name(VoxelInterpolation i);

struct VoxelFieldSettings {
  double voxel = 1;  // L_v, mm (the seed's 2, 1, 0.5)
  VoxelInterpolation interpolation = VoxelInterpolation::trilinear;
  bool prune_material_side = true;
};

class VoxelField : public ForceField {
 public:
  VoxelField(const ObstacleCloud& obstacles, const KhatibParameters& khatib, const VoxelFieldSettings& settings);
  ~VoxelField() override;
  FieldSample sample(const Eigen::Vector3d& p) const override;
  std::size_t stored_corners() const;
  std::size_t pruned_material_corners() const { return pruned_material_; }
  std::size_t memory_bytes() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  std::size_t pruned_material_ = 0;
};

}  // namespace drom::paths
