#include "paths/finish/length_bound.hpp"
#include "paths/cutter/stepover.hpp"

#include "geometry/local_geometry.hpp"
#include "geometry/surface_grid.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace drom::paths {

namespace {

template <typename... Args>
std::string fmt(const char* format, Args... args) {
  char text[200];
  std::snprintf(text, sizeof text, format, args...);
  return text;
}

}  // namespace

CuttingLengthBound shortest_cutting_length(const geometry::NurbsSurface& surface, const geometry::TrimLoops& trim, const Tool& tool, double scallop,
                                           const Kinematics& limits, int cells, const Eigen::Vector3d& axis) {
  const auto refuse = [](const std::string& what) { throw std::invalid_argument("shortest_cutting_length: " + what); };
  if (cells < 1) refuse(fmt("cells must be at least 1, got %d", cells));
  if (!(scallop > 0) || scallop > tool.corner_radius) refuse(fmt("the scallop height must lie in (0, r = %g] mm, got %g", tool.corner_radius, scallop));
  if (!(limits.feed > 0) || !std::isfinite(limits.feed)) refuse(fmt("the feed must be a positive number of mm/s, got %g", limits.feed));
  if (!axis.allFinite() || axis.norm() == 0) refuse(fmt("the tool axis must be a finite nonzero vector, got (%g, %g, %g)", axis.x(), axis.y(), axis.z()));
  const auto grid = geometry::sample_grid(surface, cells, cells, geometry::GridPlacement::cell_centres);
  const double du = (surface.u_max() - surface.u_min()) / cells, dv = (surface.v_max() - surface.v_min()) / cells;
  const double widest_anywhere = level_ground_stepover(tool, scallop);
  const Eigen::Vector3d a = axis.normalized();
  CuttingLengthBound b;
  for (std::size_t k = 0; k < grid.size(); ++k) {
    const double u = (grid.u[k] - surface.u_min()) / (surface.u_max() - surface.u_min());
    const double v = (grid.v[k] - surface.v_min()) / (surface.v_max() - surface.v_min());
    if (!trim.contains(u, v)) continue;
    const geometry::LocalGeometry& g = grid.samples[k];
    const double area = g.area_element * du * dv;
    // Eq. 1.5 is largest along the steepest slope (alpha = 0): cos^2(alpha) / (1 - sin^2(alpha) sin^2(s)) <= 1.
    const double widest = std::min(flat_stepover(scallop, effective_radius(tool, geometry::slope(g.normal, a), 0.0)), widest_anywhere);
    b.area += area;
    b.length += area / widest;
  }
  b.time = b.length / limits.feed;
  return b;
}

}  // namespace drom::paths
