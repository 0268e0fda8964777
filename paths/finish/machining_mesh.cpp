#include "paths/finish/machining_mesh.hpp"

#include "geometry/local_geometry.hpp"
#include "geometry/surface_grid.hpp"

#include <algorithm>
#include <cmath>

namespace drom::paths {

MachiningMesh build_machining_mesh(const geometry::NurbsSurface& surface, const geometry::TrimLoops& trim, double step, int sample_cells_u,
                                   int sample_cells_v, const Eigen::Vector3d& side) {
  MachiningMesh m;
  const auto [cu, cv] = geometry::cells_for_step(surface, step);
  m.cells_u = cu;
  m.cells_v = cv;
  m.sample_cells_u = sample_cells_u;
  m.sample_cells_v = sample_cells_v;
  m.surface = std::make_shared<const geometry::NurbsSurface>(surface);
  const auto grid = geometry::sample_grid(surface, cu, cv, geometry::GridPlacement::nodes);
  m.points.resize(grid.size());
  m.normals.resize(grid.size());
  m.curvature.resize(grid.size());
  double facing = 0;
  for (std::size_t k = 0; k < grid.size(); ++k) facing += grid.samples[k].normal.dot(side);
  const double sign = facing < 0 ? -1.0 : 1.0;
  for (std::size_t k = 0; k < grid.size(); ++k) {
    m.points[k] = grid.samples[k].point;
    m.normals[k] = sign * grid.samples[k].normal;
    m.curvature[k] = sign * grid.samples[k].curvature;
  }
  m.sample_cell.resize(static_cast<std::size_t>(cu * cv));
  for (int i = 0; i < cu; ++i)
    for (int j = 0; j < cv; ++j) {
      const double u = (i + 0.5) / cu, v = (j + 0.5) / cv;
      const int si = std::min(sample_cells_u - 1, static_cast<int>(u * sample_cells_u));
      const int sj = std::min(sample_cells_v - 1, static_cast<int>(v * sample_cells_v));
      m.sample_cell[static_cast<std::size_t>(m.cell(i, j))] = trim.contains(u, v) ? si * sample_cells_v + sj : -1;
    }
  return m;
}

std::vector<int> zone_cells(const MachiningMesh& mesh, const std::vector<int>& sample_zone, int zone) {
  std::vector<int> cells;
  for (int c = 0; c < mesh.cell_count(); ++c) {
    const int s = mesh.sample_cell[static_cast<std::size_t>(c)];
    if (s >= 0 && sample_zone[static_cast<std::size_t>(s)] == zone) cells.push_back(c);
  }
  return cells;
}

}  // namespace drom::paths
