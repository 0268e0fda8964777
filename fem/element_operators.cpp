#include "fem/element_operators.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <cstring>

namespace drom::fem {

Matrix6d Material::elasticity() const {
  const double E = young_modulus, nu = poisson_ratio;
  const double lambda = E * nu / ((1 + nu) * (1 - 2 * nu)), mu = E / (2 * (1 + nu));
  Matrix6d C = Matrix6d::Zero();
  C.topLeftCorner<3, 3>().setConstant(lambda);
  for (int i = 0; i < 3; ++i) {
    C(i, i) += 2 * mu;
    C(i + 3, i + 3) = mu;
  }
  return C;
}

Vector6d to_voigt(const Eigen::Matrix3d& s) {
  Vector6d v;
  v << s(0, 0), s(1, 1), s(2, 2), s(1, 2), s(0, 2), s(0, 1);
  return v;
}

double von_mises(const Vector6d& s) {
  const double a = s[0] - s[1], b = s[1] - s[2], c = s[2] - s[0];
  return std::sqrt(0.5 * (a * a + b * b + c * c) + 3 * (s[3] * s[3] + s[4] * s[4] + s[5] * s[5]));
}

ElementOperators::ElementOperators(const Mesh& mesh, const Material& material)
    : mesh_(mesh), C_(material.elasticity()), stiffness_rule_(quadrature_rule(mesh.type, is_hex(mesh.type) ? 4 : 2)) {}

void ElementOperators::strain_matrix(const Eigen::MatrixX3d& dNdx, Eigen::MatrixXd& B) {
  const auto n = dNdx.rows();
  B.setZero(6, 3 * n);
  for (Eigen::Index a = 0; a < n; ++a) {
    const double x = dNdx(a, 0), y = dNdx(a, 1), z = dNdx(a, 2);
    B(0, 3 * a) = x;
    B(1, 3 * a + 1) = y;
    B(2, 3 * a + 2) = z;
    B(3, 3 * a + 1) = z;
    B(3, 3 * a + 2) = y;
    B(4, 3 * a) = z;
    B(4, 3 * a + 2) = x;
    B(5, 3 * a) = y;
    B(5, 3 * a + 1) = x;
  }
}

Eigen::MatrixXd ElementOperators::compute_stiffness(const Eigen::Matrix3Xd& X) const {
  const auto ndof = 3 * X.cols();
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(ndof, ndof), B, CB;
  Eigen::VectorXd N;
  Eigen::MatrixX3d dN;
  for (const auto& q : stiffness_rule_) {
    shape_functions(mesh_.type, q.xi, N, dN);
    const Eigen::Matrix3d J = X * dN;
    const double det = J.determinant();
    const Eigen::MatrixX3d dNdx = dN * J.inverse();
    strain_matrix(dNdx, B);
    CB.noalias() = C_ * B;
    K.noalias() += (q.weight * det) * B.transpose() * CB;
  }
  return K;
}

const Eigen::MatrixXd& ElementOperators::stiffness(int e) {
  // Key: node coordinates relative to the first node, rounded far below any physical length. The
  // matrix is computed from the rounded coordinates themselves, so every member of a shape class
  // gets the same bits whichever is met first: results do not depend on the order of work.
  const Eigen::Matrix3Xd X = mesh_.element_nodes(e);
  Eigen::Matrix3Xd rel = X.colwise() - X.col(0);
  const double quantum = std::exp2(std::ceil(std::log2(1e-12 * std::max(1e-12, rel.cwiseAbs().maxCoeff()))));
  std::string key(static_cast<std::size_t>(rel.size()) * sizeof(long long), '\0');
  for (Eigen::Index i = 0; i < rel.size(); ++i) {
    const long long q = std::llround(rel.data()[i] / quantum);
    std::memcpy(key.data() + static_cast<std::size_t>(i) * sizeof(long long), &q, sizeof q);
    rel.data()[i] = static_cast<double>(q) * quantum;
  }
  // Cap the cache so unstructured meshes (all shapes distinct) do not hold every element matrix.
  constexpr std::size_t kMaxCached = 4096;
  if (auto it = cache_.find(key); it != cache_.end()) return stored_[it->second];
  if (cache_.size() < kMaxCached) {
    cache_.emplace(key, stored_.size());
    stored_.push_back(compute_stiffness(rel));
    return stored_.back();
  }
  scratch_ = compute_stiffness(rel);
  return scratch_;
}

Eigen::MatrixXd ElementOperators::stress_load(int e, std::span<const StressProfile> profiles, const PartShape& shape) const {
  int degree = 0;
  for (const auto& p : profiles) degree = std::max(degree, p.max_degree());
  // B is of degree 1-2 in the reference variables; curved panels add a little more.
  const auto rule = quadrature_rule(mesh_.type, degree + 2);
  const Eigen::Matrix3Xd X = mesh_.element_nodes(e);
  const auto ndof = 3 * X.cols();
  Eigen::MatrixXd f = Eigen::MatrixXd::Zero(ndof, static_cast<Eigen::Index>(profiles.size()));
  Eigen::MatrixXd B;
  Eigen::VectorXd N;
  Eigen::MatrixX3d dN;
  for (const auto& q : rule) {
    shape_functions(mesh_.type, q.xi, N, dN);
    const Eigen::Matrix3d J = X * dN;
    const double w = q.weight * J.determinant();
    strain_matrix(dN * J.inverse(), B);
    const Eigen::Vector3d x = X * N;
    for (std::size_t p = 0; p < profiles.size(); ++p)
      f.col(static_cast<Eigen::Index>(p)).noalias() += w * B.transpose() * to_voigt(profiles[p].tensor(shape, x));
  }
  return f;
}

Vector6d ElementOperators::stress_at(const Eigen::Matrix3Xd& X, const Eigen::Vector3d& xi, const Eigen::VectorXd& ue, const StressProfile* profile,
                                     const PartShape& shape, double* det_J) const {
  Eigen::MatrixXd B;
  Eigen::VectorXd N;
  Eigen::MatrixX3d dN;
  shape_functions(mesh_.type, xi, N, dN);
  const Eigen::Matrix3d J = X * dN;
  if (det_J) *det_J = J.determinant();
  strain_matrix(dN * J.inverse(), B);
  Vector6d s = C_ * (B * ue);
  if (profile) s += to_voigt(profile->tensor(shape, X * N));
  return s;
}

Vector6d ElementOperators::mean_stress(int e, const Eigen::VectorXd& ue, const StressProfile* profile, const PartShape& shape) const {
  const Eigen::Matrix3Xd X = mesh_.element_nodes(e);
  Vector6d sum = Vector6d::Zero();
  double volume = 0;
  for (const auto& q : stiffness_rule_) {
    double det_J = 0;
    const Vector6d s = stress_at(X, q.xi, ue, profile, shape, &det_J);
    sum += q.weight * det_J * s;
    volume += q.weight * det_J;
  }
  return sum / volume;
}

Vector6d ElementOperators::point_stress(int e, const Eigen::Vector3d& xi, const Eigen::VectorXd& ue, const StressProfile* profile,
                                        const PartShape& shape) const {
  return stress_at(mesh_.element_nodes(e), xi, ue, profile, shape, nullptr);
}

}  // namespace drom::fem
