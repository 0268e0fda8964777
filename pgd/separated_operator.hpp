#pragma once
// The elasticity operator of docs/design.md §3 on a TensorGrid, in separated form (seed Annex D,
// eqs. D.15-D.19): every strain component is a sum of products (in-plane operator on X) x (thickness
// operator and metric weight on Z), so with the indicator I = sum_m I_m^plane I_m^thickness the
// stiffness is sum over (m, in-plane operator pair) of A (x) B, with A a 2D matrix on the plane and B a
// 1D matrix through the thickness. Plates use Cartesian strains; cylindrical panels the strains of the
// (arc length, axial, radial) frame with their 1/r curvature terms and the r/R volume weight.
//
// Nothing of size plane x thickness is ever factorized: the PGD solver only needs
//   - the 2D matrix for fixed thickness functions S (plane_matrix),
//   - the 1D matrix for fixed plane functions R (thickness_matrix),
//   - products K u of separated fields (subtract_product), and the residual-stress load.
#include "fem/element_operators.hpp"
#include "fem/residual_stress.hpp"
#include "pgd/material_indicator.hpp"
#include "pgd/separated_field.hpp"
#include "pgd/tensor_grid.hpp"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <algorithm>
#include <array>
#include <cmath>
#include <vector>

namespace drom::pgd {

// One term of a strain component: voigt (xx, yy, zz, yz, xz, xy of the local frame, engineering
// shears) += weight(t) * (plane_op X)(u, v) * (thickness_op Z)(t) for displacement component `component`.
struct StrainTerm {
  enum Weight { One, OuterRadiusOverR, InverseR, MinusInverseR };
  int voigt, component, plane_op /*0 value, 1 d/du, 2 d/dv*/, thickness_op /*0 value, 1 d/dt*/;
  Weight weight;
};
std::vector<StrainTerm> strain_terms(bool curved);

// Held dofs as a union of products: component `component` at the in-plane nodes flagged in `plane`
// times the thickness nodes flagged in `thickness` (0/1 vectors). Held by a penalty, which keeps the
// operator separable whatever the clamp's shape.
struct PenaltyTerm {
  int component = 0;
  Eigen::VectorXd plane, thickness;
};
// Splits a list of 3D dofs (3 * Hex27 node + component) into the fewest such products.
std::vector<PenaltyTerm> penalty_terms(const TensorGrid& grid, const std::vector<int>& dofs);

class SeparatedOperator {
 public:
  SeparatedOperator(const TensorGrid& grid, const fem::Material& material);

  // Removed material keeps `ersatz` of its stiffness (not of its stress), so nodes left without
  // material stay determined without changing the rest beyond that relative amount.
  void set_indicator(const MaterialIndicator& indicator, double ersatz = 1e-9);
  // Penalty stiffness per held dof: factor * E * smallest element size.
  void set_penalty(std::vector<PenaltyTerm> terms, double factor);
  // A weak elastic foundation, stiffness per unit volume relative * E / L^2 (L the part's larger side),
  // on every component: holds a free part against rigid motion with a separable term, where 3-2-1
  // point supports would leave the 2D and 1D sub-problems singular. Its effect on the deformation is
  // of order `relative`; 0 removes it.
  void set_foundation(double relative);

  const TensorGrid& grid() const { return grid_; }
  int indicator_terms() const { return static_cast<int>(plane_factor_.size()); }

  // |r| over the dofs that are not held: the residual of eq. D.11 against test functions that vanish
  // on the clamps (the penalty's reactions are not out-of-balance forces).
  double free_norm(const ComponentTensors& r) const;
  // r -= K u, with the supports (penalty, foundation) or the elastic part only.
  void subtract_product(const SeparatedField& u, ComponentTensors& r, bool with_supports = true) const;
  // -int I eps(v) : sigma_R for a through-thickness profile (the load of docs/design.md §3 before u0).
  ComponentTensors stress_load(const fem::StressProfile& profile) const;

  // 2D operator of the Galerkin problem on (any plane functions) x span(Z_i), component by component:
  // unknowns X_i (plane_nodes x Z_i.cols()), numbered node-major in a fill-reducing order of the plane
  // (factorize it with fem::SpdSolver(keep_order = true)); lower triangle. With one column per component (Z_i = S_i) it is the 2D problem of a new
  // mode, sum_ij <S_i, K_ij S_j>; with every thickness function found so far it is the update that
  // re-solves all plane functions at once.
  const Eigen::SparseMatrix<double>& plane_matrix(const std::array<Eigen::MatrixXd, 3>& Z);
  // Its right-hand side for the load F (F_i Z_i), and its solution unpacked into the X_i.
  Eigen::VectorXd plane_load(const ComponentTensors& F, const std::array<Eigen::MatrixXd, 3>& Z) const;
  std::array<Eigen::MatrixXd, 3> plane_functions(const Eigen::VectorXd& x, const std::array<Eigen::MatrixXd, 3>& Z) const;
  Eigen::VectorXd plane_vector(const std::array<Eigen::MatrixXd, 3>& X) const;  // the inverse of plane_functions
  // 1D operator <R_i, K_ij R_j> on the 3 x thickness_nodes unknowns (dense, symmetric).
  Eigen::MatrixXd thickness_matrix(const std::array<Eigen::VectorXd, 3>& R) const;
  // Galerkin matrix of the single-component functions of a field (component 0's terms first),
  // entry (p, q) = a(phi_p, phi_q).
  Eigen::MatrixXd galerkin_matrix(const SeparatedField& basis) const;
  // sqrt(a(u, u)), supports included.
  double energy_norm(const SeparatedField& u) const { return std::sqrt(std::max(0.0, galerkin_matrix(u).sum())); }

 private:
  using Values = Eigen::Ref<const Eigen::VectorXd>;  // on the scalar plane pattern
  void multiply_plane(const Values& A, const Eigen::MatrixXd& x, Eigen::MatrixXd& y) const;  // y = A x
  int pair(int pa, int pb) const { return 3 * pa + pb; }

  TensorGrid grid_;
  fem::Matrix6d C_;
  std::vector<StrainTerm> terms_;
  // Scalar plane pattern (Quad9 connectivity), CSC with all entries.
  Eigen::SparseMatrix<double> pattern_;
  std::vector<std::array<int, 81>> element_slots_;  // nnz index of each (row a, col b) of each element
  std::array<Eigen::Matrix<double, 9, 9>, 9> plane_element_;  // per operator pair (uniform grid)
  std::array<Eigen::Matrix<double, 9, 1>, 3> plane_element_load_;
  // Per thickness element and pair of strain terms: the 3x3 integral of weights and operators.
  std::vector<std::vector<Eigen::Matrix3d>> thickness_element_;
  std::vector<double> plane_factor_sign_;          // +1 for the intact term, -(1 - ersatz) for removed
  std::vector<Eigen::VectorXd> plane_factor_, thickness_factor_;  // per indicator term
  std::vector<std::array<std::array<Eigen::MatrixXd, 9>, 9>> B_;  // [m][3 i + j][pair]
  std::vector<std::array<std::array<bool, 9>, 9>> B_nonzero_;
  std::vector<PenaltyTerm> penalty_;
  double penalty_stiffness_ = 0;
  double foundation_ = 0;
  Eigen::MatrixXd thickness_mass_;
  // Every plane operator of the current indicator as one column (9 m + pair) of values on the scalar
  // pattern, then the plane mass: the 2D matrix's blocks are this times a coefficient matrix, one
  // product per block column.
  Eigen::MatrixXd plane_operators_;
  auto plane_operator(std::size_t m, int p) const { return plane_operators_.col(static_cast<Eigen::Index>(9 * m) + p); }
  auto plane_mass() const { return plane_operators_.col(plane_operators_.cols() - 1); }
  std::vector<int> scalar_diagonal_;  // nnz index of (a, a) in pattern_
  std::vector<int> ordering_, position_;  // plane nodes in elimination order, and each node's place in it
  std::vector<std::vector<int>> sorted_slots_;  // nnz indices of each pattern_ column, rows in elimination order
  Eigen::SparseMatrix<double> plane_matrix_;  // pattern built for plane_matrix_functions_ functions
  Eigen::Index plane_matrix_functions_ = -1;
};

}  // namespace drom::pgd
