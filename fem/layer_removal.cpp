#include "fem/layer_removal.hpp"

#include "fem/shape_functions.hpp"

#include <Eigen/Dense>

#include <vector>

namespace drom::fem {

std::vector<double> layer_activity(const Mesh& mesh, const PartShape& shape, double depth, RemovalCriterion criterion) {
  const double floor_t = shape.thickness() - depth;
  std::vector<double> activity(static_cast<std::size_t>(mesh.element_count()), 1.0);
  const auto rule = is_hex(mesh.type) ? hex_gauss_rule(6) : tet_rule(10);
  Eigen::VectorXd N;
  Eigen::MatrixX3d dN;
  for (int e = 0; e < mesh.element_count(); ++e) {
    if (criterion == RemovalCriterion::Centroid) {
      activity[static_cast<std::size_t>(e)] = shape.to_parametric(mesh.centroid(e)).z() > floor_t ? 0.0 : 1.0;
      continue;
    }
    const Eigen::Matrix3Xd X = mesh.element_nodes(e);
    double kept = 0, total = 0;
    for (const auto& q : rule) {
      shape_functions(mesh.type, q.xi, N, dN);
      const double w = q.weight * (X * dN).determinant();
      total += w;
      if (shape.to_parametric(X * N).z() <= floor_t) kept += w;
    }
    activity[static_cast<std::size_t>(e)] = kept / total;
  }
  return activity;
}

PlateDistortion layer_removal_closed_form(const StressProfile& profile, double thickness, double depth, double E, double nu) {
  const double h = thickness - depth;
  std::vector<double> x, w;
  gauss_legendre(std::max(2, (profile.max_degree() + 3) / 2), x, w);  // exact for sigma(z) * z
  Eigen::Vector2d N = Eigen::Vector2d::Zero(), M = Eigen::Vector2d::Zero();
  for (std::size_t i = 0; i < x.size(); ++i) {
    const double z = 0.5 * h * (x[i] + 1), dz = 0.5 * h * w[i];
    const Eigen::Vector2d sigma = profile.evaluate(2 * z / thickness - 1);
    N += dz * sigma;
    M += dz * (z - 0.5 * h) * sigma;
  }
  // Plane-stress plate: N = E h / (1 - nu^2) Q eps, M = E h^3 / (12 (1 - nu^2)) Q kappa, Q = [1 nu; nu 1].
  Eigen::Matrix2d Q;
  Q << 1, nu, nu, 1;
  const double a = E * h / (1 - nu * nu), d = E * h * h * h / (12 * (1 - nu * nu));
  return {-Q.inverse() * N / a, -Q.inverse() * M / d};
}

Eigen::Vector2d fit_plate_curvature(const Mesh& mesh, const std::vector<int>& nodes, const Eigen::VectorXd& u) {
  Eigen::MatrixXd A(static_cast<Eigen::Index>(nodes.size()), 6);
  Eigen::VectorXd w(static_cast<Eigen::Index>(nodes.size()));
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const auto& p = mesh.nodes[static_cast<std::size_t>(nodes[i])];
    A.row(static_cast<Eigen::Index>(i)) << 1, p.x(), p.y(), p.x() * p.x(), p.x() * p.y(), p.y() * p.y();
    w[static_cast<Eigen::Index>(i)] = u[3 * nodes[i] + 2];
  }
  const Eigen::VectorXd c = A.colPivHouseholderQr().solve(w);
  return {-2 * c[3], -2 * c[5]};
}

}  // namespace drom::fem
