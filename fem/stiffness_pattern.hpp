#pragma once
// The sparsity pattern of the global stiffness (lower triangle, column-major), built once per mesh.
// Removing material never changes it: removed dofs are held (unit diagonal) rather than dropped,
// so CHOLMOD's symbolic analysis is computed once and reused for every tool station.
#include "fem/mesh.hpp"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <span>

namespace drom::fem {

class StiffnessPattern {
 public:
  explicit StiffnessPattern(const Mesh& mesh);

  // A matrix with every structural entry present and zero.
  Eigen::SparseMatrix<double> zero_matrix() const { return pattern_; }
  // K += scale * Ke over the element's dofs (lower triangle only).
  void add_element(Eigen::SparseMatrix<double>& K, std::span<const int> nodes, const Eigen::MatrixXd& Ke, double scale) const;

 private:
  Eigen::SparseMatrix<double> pattern_;
};

}  // namespace drom::fem
