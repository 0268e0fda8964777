#pragma once
// The seed's data set (Herraz §3.3): one sample point at the centre of each cell of a regular
// cells_u x cells_v parametric grid, with its point, machined-side normal, slope s and steepest
// azimuth theta; the feature vector (u, v, s, theta) clustering works on.
#include "geometry/nurbs_surface.hpp"
#include "geometry/trim_loops.hpp"

#include <Eigen/Core>

#include <vector>

namespace drom::paths {

struct SurfaceSamples {
  int cells_u = 0, cells_v = 0;  // sample (i, j), i along u, at index i * cells_v + j
  std::vector<Eigen::Vector3d> points, normals;
  std::vector<Eigen::Vector4d> features;  // (u, v, s, theta): parameters, slope (rad), azimuth reduced to [-pi/2, pi/2)
  std::vector<bool> inside;              // false outside a trimmed face's loops: not machined, in no zone
  int size() const { return cells_u * cells_v; }
  int index(int i, int j) const { return i * cells_v + j; }
};

// `side`: the machined side, as for the machining mesh (normals n with n . side >= 0 on average).
SurfaceSamples sample_surface(const geometry::NurbsSurface& surface, const geometry::TrimLoops& trim, int cells_u, int cells_v,
                              const Eigen::Vector3d& side = Eigen::Vector3d::UnitZ());

}  // namespace drom::paths
