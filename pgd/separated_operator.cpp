#include "pgd/separated_operator.hpp"

#include "fem/shape_functions.hpp"
#include "fem/spd_solver.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <map>
#include <stdexcept>

namespace drom::pgd {

namespace {

// Quadratic Lagrange basis on [-1, 1] with nodes -1, 0, 1, and derivatives.
Eigen::Vector3d line3(double x) { return {0.5 * x * (x - 1), 1 - x * x, 0.5 * x * (x + 1)}; }
Eigen::Vector3d line3_derivative(double x) { return {x - 0.5, -2 * x, x + 0.5}; }

double weight_value(StrainTerm::Weight w, double r, double outer) {
  switch (w) {
    case StrainTerm::One: return 1;
    case StrainTerm::OuterRadiusOverR: return outer / r;
    case StrainTerm::InverseR: return 1 / r;
    case StrainTerm::MinusInverseR: return -1 / r;
  }
  return 1;
}

}  // namespace

std::vector<StrainTerm> strain_terms(bool curved) {
  using W = StrainTerm;
  if (!curved)
    return {{0, 0, 1, 0, W::One}, {1, 1, 2, 0, W::One}, {2, 2, 0, 1, W::One}, {3, 1, 0, 1, W::One}, {3, 2, 2, 0, W::One},
            {4, 0, 0, 1, W::One}, {4, 2, 1, 0, W::One}, {5, 0, 2, 0, W::One}, {5, 1, 1, 0, W::One}};
  // (theta, axial, radial) frame, u = outer arc length: d/ds_physical = (R/r) d/du.
  //   e11 = (R/r) u1,u + u3 / r      e22 = u2,v      e33 = u3,t
  //   g23 = u2,t + u3,v              g13 = (R/r) u3,u + u1,t - u1 / r      g12 = (R/r) u2,u + u1,v
  return {{0, 0, 1, 0, W::OuterRadiusOverR}, {0, 2, 0, 0, W::InverseR}, {1, 1, 2, 0, W::One}, {2, 2, 0, 1, W::One},
          {3, 1, 0, 1, W::One},              {3, 2, 2, 0, W::One},      {4, 2, 1, 0, W::OuterRadiusOverR},
          {4, 0, 0, 1, W::One},              {4, 0, 0, 0, W::MinusInverseR}, {5, 1, 1, 0, W::OuterRadiusOverR},
          {5, 0, 2, 0, W::One}};
}

std::vector<PenaltyTerm> penalty_terms(const TensorGrid& grid, const std::vector<int>& dofs) {
  std::vector<PenaltyTerm> terms;
  for (int i = 0; i < 3; ++i) {
    std::vector<std::vector<int>> plane_sets(static_cast<std::size_t>(grid.thickness_nodes()));
    for (int d : dofs) {
      if (d % 3 != i) continue;
      const int node = d / 3;
      plane_sets[static_cast<std::size_t>(node / grid.plane_nodes())].push_back(node % grid.plane_nodes());
    }
    std::map<std::vector<int>, std::vector<int>> by_set;  // plane set -> thickness nodes holding it
    for (int k = 0; k < grid.thickness_nodes(); ++k) {
      auto& s = plane_sets[static_cast<std::size_t>(k)];
      if (s.empty()) continue;
      std::sort(s.begin(), s.end());
      s.erase(std::unique(s.begin(), s.end()), s.end());
      by_set[s].push_back(k);
    }
    for (const auto& [plane, thickness] : by_set) {
      PenaltyTerm t{i, Eigen::VectorXd::Zero(grid.plane_nodes()), Eigen::VectorXd::Zero(grid.thickness_nodes())};
      for (int a : plane) t.plane[a] = 1;
      for (int k : thickness) t.thickness[k] = 1;
      terms.push_back(std::move(t));
    }
  }
  return terms;
}

SeparatedOperator::SeparatedOperator(const TensorGrid& grid, const fem::Material& material)
    : grid_(grid), C_(material.elasticity()), terms_(strain_terms(grid.curved())) {
  // 1. Scalar plane pattern and each element's slots in it.
  const int n = grid_.plane_nodes();
  std::vector<Eigen::Triplet<double>> trip;
  for (int e = 0; e < grid_.plane_elements(); ++e) {
    const auto nodes = grid_.plane_element_nodes(e);
    for (int a : nodes)
      for (int b : nodes) trip.emplace_back(a, b, 1.0);
  }
  pattern_.resize(n, n);
  pattern_.setFromTriplets(trip.begin(), trip.end());
  pattern_.makeCompressed();
  auto slot = [&](int row, int col) {
    const int* begin = pattern_.innerIndexPtr() + pattern_.outerIndexPtr()[col];
    const int* end = pattern_.innerIndexPtr() + pattern_.outerIndexPtr()[col + 1];
    return static_cast<int>(std::lower_bound(begin, end, row) - pattern_.innerIndexPtr());
  };
  element_slots_.resize(static_cast<std::size_t>(grid_.plane_elements()));
  for (int e = 0; e < grid_.plane_elements(); ++e) {
    const auto nodes = grid_.plane_element_nodes(e);
    for (int r = 0; r < 9; ++r)
      for (int c = 0; c < 9; ++c) element_slots_[static_cast<std::size_t>(e)][static_cast<std::size_t>(9 * c + r)] = slot(nodes[static_cast<std::size_t>(r)], nodes[static_cast<std::size_t>(c)]);
  }

  // 2. Plane element matrices (every element is the same rectangle): 3x3 Gauss is exact for Q2 x Q2.
  std::vector<double> gx, gw;
  fem::gauss_legendre(3, gx, gw);
  const double hu = grid_.element_size_u(), hv = grid_.element_size_v();
  for (auto& m : plane_element_) m.setZero();
  for (auto& f : plane_element_load_) f.setZero();
  for (int qi = 0; qi < 3; ++qi)
    for (int qj = 0; qj < 3; ++qj) {
      const double w = gw[static_cast<std::size_t>(qi)] * gw[static_cast<std::size_t>(qj)] * 0.25 * hu * hv;
      const Eigen::Vector3d Lx = line3(gx[static_cast<std::size_t>(qi)]), Ly = line3(gx[static_cast<std::size_t>(qj)]);
      const Eigen::Vector3d dLx = line3_derivative(gx[static_cast<std::size_t>(qi)]) * (2 / hu), dLy = line3_derivative(gx[static_cast<std::size_t>(qj)]) * (2 / hv);
      std::array<Eigen::Matrix<double, 9, 1>, 3> op;
      for (int b = 0; b < 3; ++b)
        for (int a = 0; a < 3; ++a) {
          op[0][a + 3 * b] = Lx[a] * Ly[b];
          op[1][a + 3 * b] = dLx[a] * Ly[b];
          op[2][a + 3 * b] = Lx[a] * dLy[b];
        }
      for (int pa = 0; pa < 3; ++pa) {
        plane_element_load_[static_cast<std::size_t>(pa)] += w * op[static_cast<std::size_t>(pa)];
        for (int pb = 0; pb < 3; ++pb) plane_element_[static_cast<std::size_t>(pair(pa, pb))] += w * op[static_cast<std::size_t>(pa)] * op[static_cast<std::size_t>(pb)].transpose();
      }
    }

  // 3. Thickness element integrals per pair of strain terms (6 Gauss points: exact on plates, and
  //    to round-off for the smooth 1/r weights of thin panels).
  //    The same points give the foundation's thickness mass matrix.
  fem::gauss_legendre(6, gx, gw);
  const std::size_t T = terms_.size();
  thickness_element_.assign(static_cast<std::size_t>(grid_.nt), std::vector<Eigen::Matrix3d>(T * T, Eigen::Matrix3d::Zero()));
  thickness_mass_ = Eigen::MatrixXd::Zero(grid_.thickness_nodes(), grid_.thickness_nodes());
  for (int k = 0; k < grid_.nt; ++k) {
    const double t0 = grid_.levels[static_cast<std::size_t>(k)], h = grid_.levels[static_cast<std::size_t>(k + 1)] - t0;
    for (std::size_t q = 0; q < gx.size(); ++q) {
      const double t = t0 + 0.5 * h * (gx[q] + 1);
      const double r = grid_.curved() ? grid_.radius(t) : 1.0, R = grid_.curved() ? grid_.shape.outer_radius() : 1.0;
      const double w = gw[q] * 0.5 * h * (grid_.curved() ? r / R : 1.0);
      const Eigen::Vector3d op[2] = {line3(gx[q]), line3_derivative(gx[q]) * (2 / h)};
      thickness_mass_.block<3, 3>(2 * k, 2 * k) += w * op[0] * op[0].transpose();
      for (std::size_t c = 0; c < T; ++c)
        for (std::size_t d = 0; d < T; ++d) {
          const double g = weight_value(terms_[c].weight, r, R) * weight_value(terms_[d].weight, r, R);
          thickness_element_[static_cast<std::size_t>(k)][c * T + d] += w * g * op[terms_[c].thickness_op] * op[terms_[d].thickness_op].transpose();
        }
    }
  }

  scalar_diagonal_.resize(static_cast<std::size_t>(n));
  for (int a = 0; a < n; ++a) scalar_diagonal_[static_cast<std::size_t>(a)] = slot(a, a);
  // The plane's fill-reducing order, once: every 2D matrix is numbered node-major in it.
  ordering_ = fem::fill_reducing_ordering(Eigen::SparseMatrix<double>(pattern_.triangularView<Eigen::Lower>()));
  position_.resize(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) position_[static_cast<std::size_t>(ordering_[static_cast<std::size_t>(k)])] = k;
  sorted_slots_.resize(static_cast<std::size_t>(n));
  for (int a = 0; a < n; ++a) {
    auto& slots = sorted_slots_[static_cast<std::size_t>(a)];
    for (int p = pattern_.outerIndexPtr()[a]; p < pattern_.outerIndexPtr()[a + 1]; ++p) slots.push_back(p);
    std::sort(slots.begin(), slots.end(), [&](int x, int y) {
      return position_[static_cast<std::size_t>(pattern_.innerIndexPtr()[x])] < position_[static_cast<std::size_t>(pattern_.innerIndexPtr()[y])];
    });
  }

  set_indicator(MaterialIndicator::intact());
}

void SeparatedOperator::set_indicator(const MaterialIndicator& indicator, double ersatz) {
  const int M = indicator.terms();
  plane_factor_.assign(1, Eigen::VectorXd::Ones(grid_.plane_elements()));
  thickness_factor_.assign(1, Eigen::VectorXd::Ones(grid_.nt));
  plane_factor_sign_.assign(1, 1.0);
  for (std::size_t m = 0; m < indicator.removed_plane.size(); ++m) {
    plane_factor_.push_back(indicator.removed_plane[m]);
    thickness_factor_.push_back(indicator.removed_thickness[m]);
    plane_factor_sign_.push_back(-(1.0 - ersatz));
  }
  const int nz = grid_.thickness_nodes();
  const std::size_t T = terms_.size();
  plane_operators_.setZero(pattern_.nonZeros(), 9 * M + 1);
  B_.assign(static_cast<std::size_t>(M), {});
  B_nonzero_.assign(static_cast<std::size_t>(M), {});
  for (int m = 0; m < M; ++m) {
    const auto mm = static_cast<std::size_t>(m);
    for (int p = 0; p < 9; ++p) {
      auto A = plane_operators_.col(9 * m + p);
      for (int e = 0; e < grid_.plane_elements(); ++e) {
        const double a = plane_factor_sign_[mm] * plane_factor_[mm][e];
        if (a == 0) continue;
        const auto& slots = element_slots_[static_cast<std::size_t>(e)];
        const auto& Ke = plane_element_[static_cast<std::size_t>(p)];
        for (int c = 0; c < 9; ++c)
          for (int r = 0; r < 9; ++r) A[slots[static_cast<std::size_t>(9 * c + r)]] += a * Ke(r, c);
      }
    }
    for (auto& blocks : B_[mm])
      for (auto& b : blocks) b = Eigen::MatrixXd::Zero(nz, nz);
    for (auto& flags : B_nonzero_[mm]) flags.fill(false);
    for (std::size_t c = 0; c < T; ++c)
      for (std::size_t d = 0; d < T; ++d) {
        const double Ccd = C_(terms_[c].voigt, terms_[d].voigt);
        if (Ccd == 0) continue;
        const auto ij = static_cast<std::size_t>(3 * terms_[c].component + terms_[d].component);
        const auto p = static_cast<std::size_t>(pair(terms_[c].plane_op, terms_[d].plane_op));
        Eigen::MatrixXd& B = B_[mm][ij][p];
        B_nonzero_[mm][ij][p] = true;
        for (int k = 0; k < grid_.nt; ++k) {
          const double b = thickness_factor_[mm][k];
          if (b != 0) B.block<3, 3>(2 * k, 2 * k) += (Ccd * b) * thickness_element_[static_cast<std::size_t>(k)][c * T + d];
        }
      }
  }
  // The intact term (m = 0, factor 1, sign +1) of the value-value pair is the plane mass matrix.
  plane_operators_.col(9 * M) = plane_operator(0, pair(0, 0));
}

void SeparatedOperator::set_penalty(std::vector<PenaltyTerm> terms, double factor) {
  penalty_ = std::move(terms);
  penalty_stiffness_ = factor * C_(5, 5) * 2.0 * grid_.smallest_element_size();  // C(5,5) = G; 2G ~ E
}

double SeparatedOperator::free_norm(const ComponentTensors& r) const {
  if (penalty_.empty()) return norm(r);
  ComponentTensors masked = r;
  for (const auto& t : penalty_) {
    auto& m = masked[static_cast<std::size_t>(t.component)];
    for (Eigen::Index a = 0; a < m.rows(); ++a)
      if (t.plane[a] != 0)
        for (Eigen::Index k = 0; k < m.cols(); ++k)
          if (t.thickness[k] != 0) m(a, k) = 0;
  }
  return norm(masked);
}

void SeparatedOperator::set_foundation(double relative) {
  const double L = std::max(grid_.shape.length_u(), grid_.shape.length_v());
  foundation_ = relative * C_(5, 5) * 2.0 / (L * L);
}

void SeparatedOperator::multiply_plane(const Values& A, const Eigen::MatrixXd& x, Eigen::MatrixXd& y) const {
  y.setZero(x.rows(), x.cols());
  const int* outer = pattern_.outerIndexPtr();
  const int* inner = pattern_.innerIndexPtr();
  for (Eigen::Index q = 0; q < x.cols(); ++q) {
    const double* xq = x.col(q).data();
    double* yq = y.col(q).data();
    for (Eigen::Index c = 0; c < pattern_.outerSize(); ++c) {
      const double xc = xq[c];
      if (xc == 0) continue;
      for (int p = outer[c]; p < outer[c + 1]; ++p) yq[inner[p]] += A[p] * xc;
    }
  }
}

void SeparatedOperator::subtract_product(const SeparatedField& u, ComponentTensors& r, bool with_supports) const {
  const auto M = static_cast<std::size_t>(indicator_terms());
  Eigen::MatrixXd AX;
  for (int j = 0; j < 3; ++j) {
    const Eigen::MatrixXd& X = u.X[static_cast<std::size_t>(j)];
    const Eigen::MatrixXd& Z = u.Z[static_cast<std::size_t>(j)];
    const Eigen::Index Q = X.cols();
    if (Q == 0) continue;
    // Stack every (m, operator pair) product so each component's update is one matrix product.
    Eigen::MatrixXd left(X.rows(), static_cast<Eigen::Index>(9 * M) * Q);
    for (std::size_t m = 0; m < M; ++m)
      for (int p = 0; p < 9; ++p) {
        multiply_plane(plane_operator(m, p), X, AX);
        left.middleCols(static_cast<Eigen::Index>(9 * m + static_cast<std::size_t>(p)) * Q, Q) = AX;
      }
    for (int i = 0; i < 3; ++i) {
      const auto ij = static_cast<std::size_t>(3 * i + j);
      Eigen::MatrixXd right = Eigen::MatrixXd::Zero(Z.rows(), left.cols());
      bool any = false;
      for (std::size_t m = 0; m < M; ++m)
        for (int p = 0; p < 9; ++p)
          if (B_nonzero_[m][ij][static_cast<std::size_t>(p)]) {
            right.middleCols(static_cast<Eigen::Index>(9 * m + static_cast<std::size_t>(p)) * Q, Q).noalias() = B_[m][ij][static_cast<std::size_t>(p)] * Z;
            any = true;
          }
      if (any) r[static_cast<std::size_t>(i)].noalias() -= left * right.transpose();
    }
    if (!with_supports) continue;
    for (const auto& t : penalty_)
      if (t.component == j)
        r[static_cast<std::size_t>(j)].noalias() -= penalty_stiffness_ * (t.plane.asDiagonal() * X) * (t.thickness.asDiagonal() * Z).transpose();
    if (foundation_ > 0) {
      multiply_plane(plane_mass(), X, AX);
      r[static_cast<std::size_t>(j)].noalias() -= foundation_ * AX * (thickness_mass_ * Z).transpose();
    }
  }
}

ComponentTensors SeparatedOperator::stress_load(const fem::StressProfile& profile) const {
  ComponentTensors F = zero_tensors(grid_);
  const int n = grid_.plane_nodes(), nz = grid_.thickness_nodes();
  std::vector<double> gx, gw;
  fem::gauss_legendre(std::min(16, std::max(6, (profile.max_degree() + 6) / 2)), gx, gw);
  const double e = grid_.shape.thickness();
  for (std::size_t m = 0; m < plane_factor_.size(); ++m) {
    const double sign = m == 0 ? 1.0 : -1.0;  // the stress of removed material is gone entirely
    std::array<Eigen::VectorXd, 3> plane;
    for (int p = 0; p < 3; ++p) {
      plane[static_cast<std::size_t>(p)] = Eigen::VectorXd::Zero(n);
      for (int el = 0; el < grid_.plane_elements(); ++el) {
        const double a = plane_factor_[m][el];
        if (a == 0) continue;
        const auto nodes = grid_.plane_element_nodes(el);
        for (int r = 0; r < 9; ++r) plane[static_cast<std::size_t>(p)][nodes[static_cast<std::size_t>(r)]] += a * plane_element_load_[static_cast<std::size_t>(p)][r];
      }
    }
    for (const auto& term : terms_) {
      if (term.voigt > 1) continue;  // sigma_R has only the 11 and 22 components
      Eigen::VectorXd z = Eigen::VectorXd::Zero(nz);
      for (int k = 0; k < grid_.nt; ++k) {
        const double b = thickness_factor_[m][k];
        if (b == 0) continue;
        const double t0 = grid_.levels[static_cast<std::size_t>(k)], h = grid_.levels[static_cast<std::size_t>(k + 1)] - t0;
        for (std::size_t q = 0; q < gx.size(); ++q) {
          const double t = t0 + 0.5 * h * (gx[q] + 1);
          const double r = grid_.curved() ? grid_.radius(t) : 1.0, R = grid_.curved() ? grid_.shape.outer_radius() : 1.0;
          const double w = gw[q] * 0.5 * h * (grid_.curved() ? r / R : 1.0);
          const double sigma = profile.evaluate(2 * t / e - 1)[term.voigt];
          const Eigen::Vector3d op = term.thickness_op == 0 ? line3(gx[q]) : Eigen::Vector3d(line3_derivative(gx[q]) * (2 / h));
          z.segment<3>(2 * k) += (w * b * sigma * weight_value(term.weight, r, R)) * op;
        }
      }
      F[static_cast<std::size_t>(term.component)].noalias() -= sign * plane[static_cast<std::size_t>(term.plane_op)] * z.transpose();
    }
  }
  return F;
}

const Eigen::SparseMatrix<double>& SeparatedOperator::plane_matrix(const std::array<Eigen::MatrixXd, 3>& Z) {
  const int n = grid_.plane_nodes();
  const auto M = static_cast<std::size_t>(indicator_terms());
  std::vector<std::pair<std::size_t, Eigen::Index>> functions;  // (component, column of Z)
  for (std::size_t i = 0; i < 3; ++i)
    for (Eigen::Index q = 0; q < Z[i].cols(); ++q) functions.emplace_back(i, q);
  const auto F = static_cast<Eigen::Index>(functions.size());
  const int* inner = pattern_.innerIndexPtr();
  auto unknown = [&](int node, Eigen::Index I) { return static_cast<Eigen::Index>(position_[static_cast<std::size_t>(node)]) * F + I; };

  // 1. Pattern, node-major in the plane's fill-reducing order: the F unknowns of a node are
  //    consecutive, so each node is a dense block the supernodal factorization takes whole, and the
  //    order needs no search (SpdSolver keep_order). It depends on the number of functions only.
  if (plane_matrix_functions_ != F) {
    const Eigen::Index size = F * n;
    std::vector<int> col_start(static_cast<std::size_t>(size + 1), 0), rows;
    for (int pass = 0; pass < 2; ++pass) {
      std::size_t nnz = 0;
      for (int k = 0; k < n; ++k) {
        const int a = ordering_[static_cast<std::size_t>(k)];
        for (Eigen::Index J = 0; J < F; ++J) {
          const Eigen::Index c = unknown(a, J);
          if (pass == 0) col_start[static_cast<std::size_t>(c)] = static_cast<int>(nnz);
          for (int p : sorted_slots_[static_cast<std::size_t>(a)])
            for (Eigen::Index I = 0; I < F; ++I)
              if (unknown(inner[p], I) >= c) {
                if (pass == 1) rows.push_back(static_cast<int>(unknown(inner[p], I)));
                ++nnz;
              }
        }
      }
      if (pass == 0) {
        col_start[static_cast<std::size_t>(size)] = static_cast<int>(nnz);
        rows.reserve(nnz);
      }
    }
    plane_matrix_ = Eigen::SparseMatrix<double>(size, size);
    plane_matrix_.resizeNonZeros(static_cast<Eigen::Index>(rows.size()));
    std::copy(col_start.begin(), col_start.end(), plane_matrix_.outerIndexPtr());
    std::copy(rows.begin(), rows.end(), plane_matrix_.innerIndexPtr());
    plane_matrix_functions_ = F;
  }

  // 2. Values, one function J at a time: the blocks (I, J) for every I are the plane operators
  //    combined with the thickness coefficients <Z_I, B Z_J> (one matrix product), plus penalty and
  //    foundation.
  const auto P = plane_operators_.cols();
  double* val = plane_matrix_.valuePtr();
  const int* col = plane_matrix_.outerIndexPtr();
  Eigen::MatrixXd coefficients, blocks;
  for (Eigen::Index J = 0; J < F; ++J) {
    const auto [j, qj] = functions[static_cast<std::size_t>(J)];
    const Eigen::VectorXd zj = Z[j].col(qj);
    coefficients.setZero(P, F);
    for (Eigen::Index I = 0; I < F; ++I) {
      const auto [i, qi] = functions[static_cast<std::size_t>(I)];
      const Eigen::VectorXd zi = Z[i].col(qi);
      const std::size_t ij = 3 * i + j;
      for (std::size_t m = 0; m < M; ++m)
        for (int p = 0; p < 9; ++p)
          if (B_nonzero_[m][ij][static_cast<std::size_t>(p)])
            coefficients(static_cast<Eigen::Index>(9 * m) + p, I) = zi.dot(B_[m][ij][static_cast<std::size_t>(p)] * zj);
      if (i == j && foundation_ > 0) coefficients(P - 1, I) = foundation_ * zi.dot(thickness_mass_ * zj);
    }
    blocks.noalias() = plane_operators_ * coefficients;
    for (const auto& t : penalty_)
      for (Eigen::Index I = 0; I < F; ++I) {
        const auto [i, qi] = functions[static_cast<std::size_t>(I)];
        if (static_cast<int>(i) != t.component || i != j) continue;
        const double c = penalty_stiffness_ * Z[i].col(qi).dot(t.thickness.asDiagonal() * zj);
        for (int a = 0; a < n; ++a)
          if (t.plane[a] != 0) blocks(scalar_diagonal_[static_cast<std::size_t>(a)], I) += c * t.plane[a];
      }
    for (int a = 0; a < n; ++a) {
      const Eigen::Index c = unknown(a, J);
      int pos = col[c];
      for (int p : sorted_slots_[static_cast<std::size_t>(a)])
        for (Eigen::Index I = 0; I < F; ++I)
          if (unknown(inner[p], I) >= c) val[pos++] = blocks(p, I);
    }
  }
  // A function with no stiffness in this sub-problem (a component whose thickness function vanishes)
  // gets a tiny diagonal so the factorization stays defined and returns 0 for it. Only such
  // functions: a shift anywhere else would change the operator (measured: relative to the clamps'
  // penalty it left a 1e-4 residual). The diagonal is each column's first entry.
  double largest = 0;
  for (Eigen::Index c = 0; c < plane_matrix_.cols(); ++c) largest = std::max(largest, val[col[c]]);
  for (Eigen::Index J = 0; J < F; ++J) {
    double function_largest = 0;
    for (int a = 0; a < n; ++a) function_largest = std::max(function_largest, val[col[unknown(a, J)]]);
    if (function_largest > 1e-300) continue;
    for (int a = 0; a < n; ++a) val[col[unknown(a, J)]] += 1e-14 * largest;
  }
  return plane_matrix_;
}

Eigen::VectorXd SeparatedOperator::plane_load(const ComponentTensors& F, const std::array<Eigen::MatrixXd, 3>& Z) const {
  return plane_vector({F[0] * Z[0], F[1] * Z[1], F[2] * Z[2]});
}

Eigen::VectorXd SeparatedOperator::plane_vector(const std::array<Eigen::MatrixXd, 3>& X) const {
  const Eigen::Index functions = X[0].cols() + X[1].cols() + X[2].cols();
  Eigen::VectorXd b(grid_.plane_nodes() * functions);
  Eigen::Index I = 0;
  for (std::size_t i = 0; i < 3; ++i)
    for (Eigen::Index q = 0; q < X[i].cols(); ++q, ++I)
      for (int a = 0; a < grid_.plane_nodes(); ++a) b[position_[static_cast<std::size_t>(a)] * functions + I] = X[i](a, q);
  return b;
}

std::array<Eigen::MatrixXd, 3> SeparatedOperator::plane_functions(const Eigen::VectorXd& x, const std::array<Eigen::MatrixXd, 3>& Z) const {
  const Eigen::Index functions = Z[0].cols() + Z[1].cols() + Z[2].cols();
  std::array<Eigen::MatrixXd, 3> X;
  Eigen::Index I = 0;
  for (std::size_t i = 0; i < 3; ++i) {
    X[i].resize(grid_.plane_nodes(), Z[i].cols());
    for (Eigen::Index q = 0; q < Z[i].cols(); ++q, ++I)
      for (int a = 0; a < grid_.plane_nodes(); ++a) X[i](a, q) = x[position_[static_cast<std::size_t>(a)] * functions + I];
  }
  return X;
}

Eigen::MatrixXd SeparatedOperator::thickness_matrix(const std::array<Eigen::VectorXd, 3>& R) const {
  const auto M = static_cast<std::size_t>(indicator_terms());
  const int nz = grid_.thickness_nodes();
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(3 * nz, 3 * nz);
  Eigen::MatrixXd AR;
  for (std::size_t m = 0; m < M; ++m)
    for (int p = 0; p < 9; ++p)
      for (int j = 0; j < 3; ++j) {
        bool needed = false;
        for (int i = 0; i < 3; ++i) needed = needed || B_nonzero_[m][static_cast<std::size_t>(3 * i + j)][static_cast<std::size_t>(p)];
        if (!needed) continue;
        multiply_plane(plane_operator(m, p), R[static_cast<std::size_t>(j)], AR);
        for (int i = 0; i < 3; ++i) {
          const auto ij = static_cast<std::size_t>(3 * i + j);
          if (!B_nonzero_[m][ij][static_cast<std::size_t>(p)]) continue;
          K.block(i * nz, j * nz, nz, nz) += R[static_cast<std::size_t>(i)].dot(AR.col(0)) * B_[m][ij][static_cast<std::size_t>(p)];
        }
      }
  for (const auto& t : penalty_) {
    const auto& Ri = R[static_cast<std::size_t>(t.component)];
    const double c = penalty_stiffness_ * Ri.dot(t.plane.asDiagonal() * Ri);
    K.block(t.component * nz, t.component * nz, nz, nz).diagonal() += c * t.thickness;
  }
  if (foundation_ > 0) {
    Eigen::MatrixXd MR;
    for (int i = 0; i < 3; ++i) {
      multiply_plane(plane_mass(), R[static_cast<std::size_t>(i)], MR);
      K.block(i * nz, i * nz, nz, nz) += foundation_ * R[static_cast<std::size_t>(i)].dot(MR.col(0)) * thickness_mass_;
    }
  }
  for (int i = 0; i < 3; ++i) {  // as in plane_matrix: a diagonal for components without stiffness only
    auto d = K.diagonal().segment(i * nz, nz);
    if (d.maxCoeff() <= 1e-300) d.array() += 1e-14 * K.diagonal().maxCoeff();
  }
  return K;
}

Eigen::MatrixXd SeparatedOperator::galerkin_matrix(const SeparatedField& basis) const {
  // Every term a(phi_p, phi_q) of two single-component sets factors as (X_i^T A X_j) times (Z_i^T B Z_j).
  std::array<Eigen::Index, 4> offset{0, 0, 0, 0};
  for (int i = 0; i < 3; ++i) offset[static_cast<std::size_t>(i + 1)] = offset[static_cast<std::size_t>(i)] + basis.terms(i);
  Eigen::MatrixXd G = Eigen::MatrixXd::Zero(offset[3], offset[3]);
  auto add = [&](std::size_t i, std::size_t j, const Eigen::MatrixXd& plane, const Eigen::MatrixXd& thickness) {
    G.block(offset[i], offset[j], plane.rows(), plane.cols()) += plane.cwiseProduct(thickness);
  };
  Eigen::MatrixXd AX;
  for (std::size_t m = 0; m < static_cast<std::size_t>(indicator_terms()); ++m)
    for (int p = 0; p < 9; ++p)
      for (std::size_t j = 0; j < 3; ++j) {
        if (basis.X[j].cols() == 0) continue;
        bool computed = false;
        for (std::size_t i = 0; i < 3; ++i) {
          const std::size_t ij = 3 * i + j;
          if (!B_nonzero_[m][ij][static_cast<std::size_t>(p)] || basis.X[i].cols() == 0) continue;
          if (!computed) multiply_plane(plane_operator(m, p), basis.X[j], AX), computed = true;
          add(i, j, basis.X[i].transpose() * AX, basis.Z[i].transpose() * B_[m][ij][static_cast<std::size_t>(p)] * basis.Z[j]);
        }
      }
  for (const auto& t : penalty_) {
    const auto i = static_cast<std::size_t>(t.component);
    if (basis.X[i].cols() == 0) continue;
    add(i, i, penalty_stiffness_ * basis.X[i].transpose() * t.plane.asDiagonal() * basis.X[i], basis.Z[i].transpose() * t.thickness.asDiagonal() * basis.Z[i]);
  }
  if (foundation_ > 0)
    for (std::size_t i = 0; i < 3; ++i) {
      if (basis.X[i].cols() == 0) continue;
      multiply_plane(plane_mass(), basis.X[i], AX);
      add(i, i, foundation_ * basis.X[i].transpose() * AX, basis.Z[i].transpose() * thickness_mass_ * basis.Z[i]);
    }
  return G;
}

}  // namespace drom::pgd
