// fem::SpdSolver's work counts: the PGD bench sets FE's factorization against the PGD's by them, so
// they must be the textbook count, sum over columns of (nonzeros of L's column)^2, and nnz(L).
#include "fem/spd_solver.hpp"

#include <Eigen/SparseCore>
#include <gtest/gtest.h>

#include <vector>

using namespace drom;

namespace {

Eigen::SparseMatrix<double> lower_triangle(int n, bool dense) {
  std::vector<Eigen::Triplet<double>> t;
  for (int j = 0; j < n; ++j)
    for (int i = j; i < (dense ? n : std::min(n, j + 2)); ++i) t.emplace_back(i, j, i == j ? 2.0 * n : -1.0);
  Eigen::SparseMatrix<double> A(n, n);
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

}  // namespace

TEST(SpdSolver, ReportsTheFactorsNonzerosAndFlopsOfItsOrder) {
  // In its own order a tridiagonal matrix's L has columns of 2 nonzeros (the last 1); a dense one's
  // column j has n - j.
  for (const auto& [n, dense, nonzeros, flops] : {std::tuple{200, false, 399.0, 4.0 * 199 + 1}, std::tuple{10, true, 55.0, 385.0}}) {
    const Eigen::SparseMatrix<double> A = lower_triangle(n, dense);
    fem::SpdSolver solver(true);
    solver.factorize(A);
    EXPECT_EQ(solver.stats().factor_nonzeros, nonzeros) << n;
    EXPECT_EQ(solver.stats().factor_flops, flops) << n;
    const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(n, 1, 2);
    const Eigen::VectorXd x = solver.solve(b);
    EXPECT_LT((A.selfadjointView<Eigen::Lower>() * x - b).norm(), 1e-12 * b.norm()) << n;
  }
}
