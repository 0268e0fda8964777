#pragma once
// The seed's two Bézier test surfaces (Herraz 2021, Tables 2.2 and 2.4), for tests.
#include "geometry/nurbs_surface.hpp"

#include <string>

namespace drom::tests {

inline geometry::NurbsSurface rubio_surface() {
  return geometry::NurbsSurface::bezier(3, 3, {{0, -15.32, -12.85}, {0, -6.42, 7.66}, {0, 15.32, 12.85},
                                               {40, -18.53, -9.02}, {40, -9.64, 11.49}, {40, 12.10, 16.68},
                                               {80, -28.17, 2.46}, {80, -22.49, 26.81}, {80, 2.46, 28.17}});
}

inline geometry::NurbsSurface choi_surface() {
  const double x[4][4] = {{7.92, 6.33, 6.33, 7.92}, {23.72, 22.14, 22.14, 23.72}, {42.70, 41.12, 41.12, 42.70}, {56.02, 54.44, 54.44, 56.02}};
  const double z[4][4] = {{37.26, 29.81, 29.81, 37.26}, {26.11, 18.66, 18.66, 26.11}, {29.87, 22.42, 22.42, 29.87}, {19.25, 11.79, 11.79, 19.25}};
  std::vector<Eigen::Vector3d> points;
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) points.emplace_back(x[i][j], 20.4 * j, z[i][j]);
  return geometry::NurbsSurface::bezier(4, 4, points);
}

inline std::string rubio_toml() {
  return "[surface]\nkind = \"bezier\"\ncount = [3, 3]\npoints = [\n"
         "  [0, -15.32, -12.85], [0, -6.42, 7.66], [0, 15.32, 12.85],\n"
         "  [40, -18.53, -9.02], [40, -9.64, 11.49], [40, 12.10, 16.68],\n"
         "  [80, -28.17, 2.46], [80, -22.49, 26.81], [80, 2.46, 28.17]]\n";
}

}  // namespace drom::tests
