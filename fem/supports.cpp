#include "fem/supports.hpp"

#include <Eigen/Dense>

#include <limits>
#include <stdexcept>

namespace drom::fem {

std::vector<int> isostatic_dofs(const Mesh& mesh, const PartShape& shape, const std::vector<char>& live) {
  const Eigen::Vector3d targets[3] = {{0, 0, 0}, {shape.length_u(), 0, 0}, {0, shape.length_v(), 0}};
  int chosen[3] = {-1, -1, -1};
  for (int k = 0; k < 3; ++k) {
    double best = std::numeric_limits<double>::infinity();
    for (int n = 0; n < mesh.node_count(); ++n) {
      if (!live[static_cast<std::size_t>(n)]) continue;
      const double d = (shape.to_parametric(mesh.nodes[static_cast<std::size_t>(n)]) - targets[k]).squaredNorm();
      if (d < best) {
        best = d;
        chosen[k] = n;
      }
    }
    if (chosen[k] < 0) throw std::runtime_error("isostatic_dofs: no live node left");
  }
  if (chosen[0] == chosen[1] || chosen[0] == chosen[2] || chosen[1] == chosen[2])
    throw std::runtime_error("isostatic_dofs: the part is too small to place three distinct supports");
  return {3 * chosen[0], 3 * chosen[0] + 1, 3 * chosen[0] + 2, 3 * chosen[1] + 1, 3 * chosen[1] + 2, 3 * chosen[2] + 2};
}

Eigen::Matrix<double, 6, 1> remove_rigid_motion(const Mesh& mesh, const std::vector<int>& nodes, Eigen::VectorXd& u) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int n : nodes) c += mesh.nodes[static_cast<std::size_t>(n)];
  c /= static_cast<double>(nodes.size());
  // u_n ~ t + w x r_n = t - [r_n]x w
  Eigen::Matrix<double, 6, 6> A = Eigen::Matrix<double, 6, 6>::Zero();
  Eigen::Matrix<double, 6, 1> b = Eigen::Matrix<double, 6, 1>::Zero();
  for (int n : nodes) {
    const Eigen::Vector3d r = mesh.nodes[static_cast<std::size_t>(n)] - c;
    Eigen::Matrix<double, 3, 6> G;
    G << 1, 0, 0, 0, r.z(), -r.y(),  //
        0, 1, 0, -r.z(), 0, r.x(),   //
        0, 0, 1, r.y(), -r.x(), 0;
    A += G.transpose() * G;
    b += G.transpose() * u.segment<3>(3 * n);
  }
  const Eigen::Matrix<double, 6, 1> tw = A.ldlt().solve(b);
  for (int n = 0; n < mesh.node_count(); ++n) {
    const Eigen::Vector3d r = mesh.nodes[static_cast<std::size_t>(n)] - c;
    u.segment<3>(3 * n) -= tw.head<3>() + tw.tail<3>().cross(r);
  }
  return tw;
}

}  // namespace drom::fem
