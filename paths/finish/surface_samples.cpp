#include "paths/finish/surface_samples.hpp"

#include "geometry/local_geometry.hpp"
#include "geometry/surface_grid.hpp"

namespace drom::paths {

SurfaceSamples sample_surface(const geometry::NurbsSurface& surface, const geometry::TrimLoops& trim, int cells_u, int cells_v, const Eigen::Vector3d& side) {
  const auto grid = geometry::sample_grid(surface, cells_u, cells_v, geometry::GridPlacement::cell_centres);
  SurfaceSamples s;
  s.cells_u = cells_u;
  s.cells_v = cells_v;
  double facing = 0;
  for (const auto& g : grid.samples) facing += g.normal.dot(side);
  const double sign = facing < 0 ? -1.0 : 1.0;
  for (std::size_t k = 0; k < grid.size(); ++k) {
    const Eigen::Vector3d n = sign * grid.samples[k].normal;
    const double u = (grid.u[k] - surface.u_min()) / (surface.u_max() - surface.u_min());
    const double v = (grid.v[k] - surface.v_min()) / (surface.v_max() - surface.v_min());
    s.points.push_back(grid.samples[k].point);
    s.normals.push_back(n);
    s.features.emplace_back(u, v, geometry::slope(n, Eigen::Vector3d::UnitZ()), geometry::steepest_azimuth(n));
    s.inside.push_back(trim.contains(u, v));
  }
  return s;
}

}  // namespace drom::paths
