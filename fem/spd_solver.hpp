#pragma once
// Sparse SPD solves with CHOLMOD's supernodal Cholesky. The symbolic analysis is done once per
// pattern; numeric refactorization and multi-right-hand-side solves reuse it.
#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <memory>
#include <vector>

namespace drom::fem {

struct SolverStats {
  double analyze_seconds = 0, factorize_seconds = 0, solve_seconds = 0;
  std::size_t factor_peak_bytes = 0;  // CHOLMOD's own peak memory
  double factor_flops = 0, factor_nonzeros = 0;  // of one numeric factorization of the analyzed pattern (CHOLMOD fl, lnz)
  int factorizations = 0;
};

// A fill-reducing ordering of a symmetric pattern (lower triangle given), as CHOLMOD would choose it:
// ordering[k] = the row/column eliminated k-th. `flops`, if given: CHOLMOD's flop count of a
// factorization in that order.
std::vector<int> fill_reducing_ordering(Eigen::SparseMatrix<double> lower, double* flops = nullptr);

class SpdSolver {
 public:
  // keep_order: factorize in the matrix's own order (the caller numbered it for low fill, e.g. by
  // fill_reducing_ordering): no ordering search at analysis.
  explicit SpdSolver(bool keep_order = false);
  ~SpdSolver();
  SpdSolver(SpdSolver&&) noexcept;
  SpdSolver& operator=(SpdSolver&&) noexcept;

  // K: lower triangle. Analyzes the pattern on first use, then factorizes numerically.
  // Throws std::runtime_error if K is not positive definite (a mechanism left unconstrained).
  void factorize(const Eigen::SparseMatrix<double>& K);
  Eigen::MatrixXd solve(const Eigen::MatrixXd& rhs);
  const SolverStats& stats() const { return stats_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  SolverStats stats_;
};

}  // namespace drom::fem
