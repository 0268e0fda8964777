#pragma once
// The surface as path planning sees it: an iso-parametric mesh whose lines are about `step` apart
// on the surface (the seed's 0.5 mm machining mesh), each node with its point, the normal on the
// machined side and the curvature tensor; each mesh cell knows which sample cell (the clustering
// grid) holds its centre, and whether it lies inside the face's trimming loops.
#include "geometry/nurbs_surface.hpp"
#include "geometry/trim_loops.hpp"

#include <Eigen/Core>

#include <memory>
#include <vector>

namespace drom::paths {

struct MachiningMesh {
  int cells_u = 0, cells_v = 0;  // mesh cells; nodes are (cells_u + 1) x (cells_v + 1)
  // Node (i, j), i along u, is at index i * (cells_v + 1) + j.
  std::vector<Eigen::Vector3d> points, normals;  // normals on the machined side
  std::vector<Eigen::Matrix3d> curvature;        // normal curvature t' C t, positive where the surface bends towards the tool side
  // Mesh cell (i, j) at index i * cells_v + j: the sample cell holding its centre, -1 outside the trim.
  std::vector<int> sample_cell;
  int sample_cells_u = 0, sample_cells_v = 0;
  std::shared_ptr<const geometry::NurbsSurface> surface;  // what the mesh samples (for the exact variant)

  // The parameters of node (i, j).
  double node_u(int i) const { return surface->u_min() + (surface->u_max() - surface->u_min()) * i / cells_u; }
  double node_v(int j) const { return surface->v_min() + (surface->v_max() - surface->v_min()) * j / cells_v; }

  int node(int i, int j) const { return i * (cells_v + 1) + j; }
  int cell(int i, int j) const { return i * cells_v + j; }
  int node_count() const { return (cells_u + 1) * (cells_v + 1); }
  int cell_count() const { return cells_u * cells_v; }
};

// `side` picks the machined side: normals n with n . side >= 0 on average (the tool's side in the
// part's own frame, +Z for a part set up for 3-axis finishing). Throws std::domain_error on a
// degenerate patch.
MachiningMesh build_machining_mesh(const geometry::NurbsSurface& surface, const geometry::TrimLoops& trim, double step, int sample_cells_u,
                                   int sample_cells_v, const Eigen::Vector3d& side = Eigen::Vector3d::UnitZ());

// The mesh cells whose sample cell has zone `zone` in `sample_zone` (one id per sample cell).
std::vector<int> zone_cells(const MachiningMesh& mesh, const std::vector<int>& sample_zone, int zone);

}  // namespace drom::paths
