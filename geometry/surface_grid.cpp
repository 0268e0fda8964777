#include "geometry/surface_grid.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace drom::geometry {

SurfaceGrid sample_grid(const NurbsSurface& surface, int cells_u, int cells_v, GridPlacement placement) {
  if (cells_u < 1 || cells_v < 1) throw std::invalid_argument("a sampling grid needs at least one cell each way");
  SurfaceGrid g;
  const bool nodes = placement == GridPlacement::nodes;
  g.count_u = nodes ? cells_u + 1 : cells_u;
  g.count_v = nodes ? cells_v + 1 : cells_v;
  const double u0 = surface.u_min(), du = (surface.u_max() - u0) / cells_u;
  const double v0 = surface.v_min(), dv = (surface.v_max() - v0) / cells_v;
  const double offset = nodes ? 0.0 : 0.5;
  const std::size_t n = static_cast<std::size_t>(g.count_u) * static_cast<std::size_t>(g.count_v);
  g.u.resize(n);
  g.v.resize(n);
  g.samples.resize(n);
  for (int i = 0; i < g.count_u; ++i)
    for (int j = 0; j < g.count_v; ++j) {
      const std::size_t k = g.index(i, j);
      g.u[k] = u0 + (i + offset) * du;
      g.v[k] = v0 + (j + offset) * dv;
      g.samples[k] = local_geometry(surface.derivatives(g.u[k], g.v[k]));
    }
  return g;
}

std::pair<double, double> longest_iso_curves(const NurbsSurface& surface) {
  constexpr int kProbe = 32;  // iso-curves measured, and points along each
  double longest_u = 0, longest_v = 0;
  for (int a = 0; a <= kProbe; ++a) {
    const double s = static_cast<double>(a) / kProbe;
    double lu = 0, lv = 0;
    Eigen::Vector3d pu = surface.point(surface.u_min(), surface.v_min() + s * (surface.v_max() - surface.v_min()));
    Eigen::Vector3d pv = surface.point(surface.u_min() + s * (surface.u_max() - surface.u_min()), surface.v_min());
    for (int b = 1; b <= kProbe; ++b) {
      const double t = static_cast<double>(b) / kProbe;
      const Eigen::Vector3d qu = surface.point(surface.u_min() + t * (surface.u_max() - surface.u_min()), surface.v_min() + s * (surface.v_max() - surface.v_min()));
      const Eigen::Vector3d qv = surface.point(surface.u_min() + s * (surface.u_max() - surface.u_min()), surface.v_min() + t * (surface.v_max() - surface.v_min()));
      lu += (qu - pu).norm();
      lv += (qv - pv).norm();
      pu = qu;
      pv = qv;
    }
    longest_u = std::max(longest_u, lu);
    longest_v = std::max(longest_v, lv);
  }
  return {longest_u, longest_v};
}

std::pair<int, int> cells_for_step(const NurbsSurface& surface, double step) {
  if (!(step > 0)) throw std::invalid_argument("the mesh step must be positive");
  const auto [lu, lv] = longest_iso_curves(surface);
  // Past 10^6 cells a side the grid could not be held anyway (and the count must fit an int).
  constexpr double kMaxCells = 1e6;
  if (!(lu / step <= kMaxCells) || !(lv / step <= kMaxCells)) throw std::invalid_argument("the mesh step is too small for this surface (over 10^6 cells a side)");
  return {std::max(1, static_cast<int>(std::ceil(lu / step))), std::max(1, static_cast<int>(std::ceil(lv / step)))};
}

}  // namespace drom::geometry
