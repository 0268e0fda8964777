#pragma once
// Cholesky of a stiffness whose later changes stay inside a known set of dofs, the block B (what the
// tool will touch over the next stations). B is eliminated last, so the part of the factor that
// eliminates the rest R never changes:
//
//   K = [K_RR  K_RB]   L = [L_RR   0  ]   S = K_BB - L_BR L_BR^T = L_BB L_BB^T (m x m, dense)
//       [K_BR  K_BB]       [L_BR  L_BB]
//
// A change dK confined to B x B changes only S: the station refactorizes S + dK, at most m x m and
// usually only its trailing part, instead of the whole matrix, and a solve runs the anchor's sparse
// triangular factors around that dense one.
// The answer is the full factorization's, with another elimination order's round-off.
#include "fem/spd_solver.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <functional>
#include <memory>
#include <span>
#include <vector>

namespace drom::fem {

class TrailingBlockCholesky {
 public:
  TrailingBlockCholesky();
  ~TrailingBlockCholesky();
  TrailingBlockCholesky(const TrailingBlockCholesky&) = delete;
  TrailingBlockCholesky& operator=(const TrailingBlockCholesky&) = delete;

  // K: lower triangle. block: the dofs later changes may touch (any order; kept as given: block index
  // b is dof block[b]). ordering: a fill-reducing order of K's pattern (fill_reducing_ordering); R
  // keeps its relative order, B goes after it. Returns false, holding no factor, if CHOLMOD cannot
  // analyze or factorize it (e.g. too large); throws std::runtime_error if K is not positive definite.
  bool factorize_anchor(const Eigen::SparseMatrix<double>& K, std::span<const int> block, const std::vector<int>& ordering);
  // Refactorizes S after a change confined to block indices first .. m - 1 (rows and columns) since
  // the last factorization (the anchor's, or the last refactorize_trailing's). `change` gets T, the
  // Schur complement of the current S on those indices ((m - first)^2, index 0 is block index
  // `first`; its lower triangle holds it), and adds the change to it; it may also overwrite whole
  // rows and columns, as held dofs are. The leading columns of S's factor stay; only T is
  // refactorized, (m - first)^3 / 3 flops, and forming T costs at most as much again: less when
  // `first` moved on by little since the last call, which then only downdates its T. Ordering B by
  // the last station that changes each dof keeps `first` high. Returns false, keeping the current
  // S, if the changed one is not positive definite.
  bool refactorize_trailing(Eigen::Index first, const std::function<void(Eigen::Ref<Eigen::MatrixXd>)>& change);
  // Back to the anchor's S: the next refactorize_trailing's change is measured from the anchor.
  void reset_to_anchor();
  // Solves the current matrix for each column.
  Eigen::MatrixXd solve(const Eigen::MatrixXd& rhs);

  Eigen::Index block_size() const { return static_cast<Eigen::Index>(block_.size()); }
  const std::vector<int>& block() const { return block_; }
  // Dofs refactorized (m - first), summed over the refactorize_trailing calls.
  long long trailing_dofs() const { return trailing_dofs_; }
  double anchor_seconds() const { return anchor_seconds_; }
  double refactorize_seconds() const { return refactorize_seconds_; }
  double solve_seconds() const { return solve_seconds_; }
  int forward_solves() const { return forward_solves_; }

 private:
  struct Cholmod;
  std::unique_ptr<Cholmod> cholmod_;
  std::vector<int> order_;  // order_[k]: the dof eliminated k-th
  std::vector<int> block_;
  Eigen::MatrixXd lower_bb_;      // L_BB of the anchor
  Eigen::MatrixXd schur_factor_;  // the Cholesky factor of the current S (lower), unless S is the anchor's (L_BB is its factor)
  bool schur_is_anchor_ = true;
  Eigen::MatrixXd trailing_;      // the last T refactorize_trailing factorized (lower triangle), from block index trailing_start_
  Eigen::Index trailing_start_ = 0;
  struct KeptForward {
    Eigen::MatrixXd f_r, forward;  // f_R and the forward solve of [f_R; 0]
    Eigen::MatrixXd coupling;      // L_BB times the forward solve's B part: -L_BR y
  };
  std::vector<KeptForward> kept_;
  int forward_solves_ = 0;
  long long trailing_dofs_ = 0;
  double anchor_seconds_ = 0, refactorize_seconds_ = 0, solve_seconds_ = 0;
};

}  // namespace drom::fem
