#pragma once
// A surface sampled on a regular parametric grid: the cell centres of a cells_u x cells_v grid (the
// seed's sample points, one per cell) or the grid's nodes (a mesh of iso-parametric lines).
#include "geometry/local_geometry.hpp"
#include "geometry/nurbs_surface.hpp"

#include <vector>

namespace drom::geometry {

enum class GridPlacement { cell_centres, nodes };

struct SurfaceGrid {
  int count_u = 0, count_v = 0;  // samples along u and along v
  // Sample (i, j), i along u, is at index i * count_v + j.
  std::vector<double> u, v;
  std::vector<LocalGeometry> samples;
  std::size_t index(int i, int j) const { return static_cast<std::size_t>(i) * static_cast<std::size_t>(count_v) + static_cast<std::size_t>(j); }
  std::size_t size() const { return samples.size(); }
};

// Throws std::domain_error where the surface has no normal (a degenerate patch).
SurfaceGrid sample_grid(const NurbsSurface& surface, int cells_u, int cells_v, GridPlacement placement);

// The longest iso-curve along u and along v (mm), measured on a coarse polygon.
std::pair<double, double> longest_iso_curves(const NurbsSurface& surface);
// Cell counts along u and v whose iso-lines are about `step` apart on the surface (the longest
// iso-curve in each direction), at least 1 each. Throws std::invalid_argument past 10^6 a side.
std::pair<int, int> cells_for_step(const NurbsSurface& surface, double step);

}  // namespace drom::geometry
