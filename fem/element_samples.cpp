#include "fem/element_samples.hpp"

#include "fem/shape_functions.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>

namespace drom::fem {

namespace {
int points_for(double extent, double spacing, int at_least) {
  return std::clamp(static_cast<int>(std::ceil(extent / spacing)), at_least, 24);
}

// Uniform midpoint grid on [-1, 1]^3: with a linear ramp one cell wide, a planar cut is integrated
// exactly (Gauss points are not uniformly spaced, so their cells are not a fixed width).
std::vector<QuadraturePoint> midpoint_grid(int nx, int ny, int nz) {
  std::vector<QuadraturePoint> rule;
  const double w = 8.0 / (nx * ny * nz);
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) rule.push_back({Eigen::Vector3d(-1 + (2 * i + 1.0) / nx, -1 + (2 * j + 1.0) / ny, -1 + (2 * k + 1.0) / nz), w});
  return rule;
}
}  // namespace

levelset::ElementSamples element_samples(const Mesh& mesh, double spacing) {
  levelset::ElementSamples samples;
  const auto n = static_cast<std::size_t>(mesh.element_count());
  samples.centroid.resize(n);
  samples.bounds.resize(n);
  samples.points.resize(n);
  samples.weights.resize(n);
  samples.cell.assign(n, Eigen::Matrix3d::Zero());
  Eigen::VectorXd N;
  Eigen::MatrixX3d dN;
  for (int e = 0; e < mesh.element_count(); ++e) {
    const auto k = static_cast<std::size_t>(e);
    const Eigen::Matrix3Xd X = mesh.element_nodes(e);
    samples.centroid[k] = mesh.centroid(e);
    samples.bounds[k] = Eigen::AlignedBox3d(X.rowwise().minCoeff(), X.rowwise().maxCoeff());
    std::vector<QuadraturePoint> rule;
    if (is_hex(mesh.type)) {
      // Extent along each reference direction from the Jacobian at the centre.
      shape_functions(mesh.type, Eigen::Vector3d::Zero(), N, dN);
      const Eigen::Matrix3d J = X * dN;
      const int nx = points_for(2 * J.col(0).norm(), spacing, 1), ny = points_for(2 * J.col(1).norm(), spacing, 1),
                nz = points_for(2 * J.col(2).norm(), spacing, 1);
      rule = midpoint_grid(nx, ny, nz);
      samples.cell[k].col(0) = 2.0 / nx * J.col(0);
      samples.cell[k].col(1) = 2.0 / ny * J.col(1);
      samples.cell[k].col(2) = 2.0 / nz * J.col(2);
    } else {
      double longest = 0;
      for (int a = 0; a < 4; ++a)
        for (int b = a + 1; b < 4; ++b) longest = std::max(longest, (X.col(a) - X.col(b)).norm());
      rule = tet_rule(2 * points_for(longest, spacing, 2) - 1);
    }
    for (const auto& q : rule) {
      shape_functions(mesh.type, q.xi, N, dN);
      samples.points[k].push_back(X * N);
      samples.weights[k].push_back(q.weight * (X * dN).determinant());
    }
  }
  return samples;
}

}  // namespace drom::fem
