#pragma once
// A flat lx x ly plate's final surface for the loop's tests: an nx x ny grid of upward quads centred
// on the origin at z = 0, plus one side face (normal along Y, down to side_z), which every upward
// filter must leave out. Displacement and sd zero.
#include "online/predictor.hpp"

#include <Eigen/Core>

namespace drom::test {

inline online::FinalShape plate_shape(int nx, int ny, double lx, double ly, double side_z) {
  online::FinalShape s;
  s.nodes.resize(3, (nx + 1) * (ny + 1));
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) s.nodes.col(j * (nx + 1) + i) = Eigen::Vector3d(lx * i / nx - lx / 2, ly * j / ny - ly / 2, 0);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const int a = j * (nx + 1) + i;
      s.faces.insert(s.faces.end(), {a, a + 1, a + nx + 2, a + nx + 1});
    }
  const int base = static_cast<int>(s.nodes.cols());
  s.nodes.conservativeResize(3, base + 2);
  s.nodes.col(base) = Eigen::Vector3d(-lx / 2, -ly / 2, side_z), s.nodes.col(base + 1) = Eigen::Vector3d(-lx / 2 + lx / nx, -ly / 2, side_z);
  s.faces.insert(s.faces.end(), {base, base + 1, 1, 0});
  s.face_nodes = 4;
  s.displacement = s.sd = Eigen::Matrix3Xd::Zero(3, s.nodes.cols());
  return s;
}

}  // namespace drom::test
