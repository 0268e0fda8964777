#include "fem/trailing_block_cholesky.hpp"

#include "support/resources.hpp"

#include <Eigen/CholmodSupport>

#include <algorithm>
#include <chrono>
#include <functional>
#include <iterator>
#include <limits>
#include <string>
#include <stdexcept>

// LAPACK and BLAS, Fortran interfaces (no LAPACKE in Debian's base packages): the trailing size_t
// arguments are the hidden lengths of the character arguments.
extern "C" {
void dpotrf_(const char* uplo, const int* n, double* a, const int* lda, int* info, std::size_t uplo_length);
void dpotrs_(const char* uplo, const int* n, const int* nrhs, const double* a, const int* lda, double* b, const int* ldb, int* info,
             std::size_t uplo_length);
void dtrmm_(const char* side, const char* uplo, const char* transa, const char* diag, const int* m, const int* n, const double* alpha, const double* a,
            const int* lda, double* b, const int* ldb, std::size_t side_length, std::size_t uplo_length, std::size_t transa_length, std::size_t diag_length);
void dtrsm_(const char* side, const char* uplo, const char* transa, const char* diag, const int* m, const int* n, const double* alpha, const double* a,
            const int* lda, double* b, const int* ldb, std::size_t side_length, std::size_t uplo_length, std::size_t transa_length, std::size_t diag_length);
void dlauum_(const char* uplo, const int* n, double* a, const int* lda, int* info, std::size_t uplo_length);
void dsyrk_(const char* uplo, const char* trans, const int* n, const int* k, const double* alpha, const double* a, const int* lda, const double* beta,
            double* c, const int* ldc, std::size_t uplo_length, std::size_t trans_length);
}

namespace drom::fem {

namespace lapack {
namespace {

int size_of(Eigen::Index n) {
  if (n > std::numeric_limits<int>::max()) throw std::length_error("LAPACK: matrix too large");
  return static_cast<int>(n);
}

// A = L L^T in place (the lower triangle; the strict upper one is left as it was). False if A is not
// positive definite.
bool cholesky_lower(Eigen::MatrixXd& a) {
  const int n = size_of(a.rows());
  int info = 0;
  if (n > 0) dpotrf_("L", &n, a.data(), &n, &info, 1);
  if (info < 0) throw std::logic_error("dpotrf: bad argument " + std::to_string(-info));
  return info == 0;
}

// B := (L L^T)^-1 B with L from cholesky_lower.
void cholesky_solve(const Eigen::MatrixXd& factor, Eigen::MatrixXd& b) {
  const int n = size_of(factor.rows()), nrhs = size_of(b.cols());
  int info = 0;
  if (n > 0 && nrhs > 0) dpotrs_("L", &n, &nrhs, factor.data(), &n, b.data(), &n, &info, 1);
  if (info != 0) throw std::logic_error("dpotrs: bad argument " + std::to_string(-info));
}

// B := op(L) B or op(L)^-1 B, L lower triangular (n x n), B n x k inside an array of leading
// dimension ldb; op is the transpose if `transpose`.
void triangular_multiply(const Eigen::MatrixXd& lower, bool transpose, Eigen::Index k, double* b, Eigen::Index ldb) {
  const int n = size_of(lower.rows()), kk = size_of(k), lb = size_of(ldb);
  const double one = 1;
  if (n > 0 && kk > 0) dtrmm_("L", "L", transpose ? "T" : "N", "N", &n, &kk, &one, lower.data(), &n, b, &lb, 1, 1, 1, 1);
}
void triangular_solve(const Eigen::MatrixXd& lower, Eigen::Index k, double* b, Eigen::Index ldb) {
  const int n = size_of(lower.rows()), kk = size_of(k), lb = size_of(ldb);
  const double one = 1;
  if (n > 0 && kk > 0) dtrsm_("L", "L", "N", "N", &n, &kk, &one, lower.data(), &n, b, &lb, 1, 1, 1, 1);
}

// The lower triangle of C += sign A A^T (C n x n, A n x k; both inside column-major arrays of
// leading dimensions ldc and lda).
void add_product(double sign, Eigen::Index n, Eigen::Index k, const double* a, Eigen::Index lda, double* c, Eigen::Index ldc) {
  const int nn = size_of(n), kk = size_of(k), la = size_of(lda), lc = size_of(ldc);
  const double one = 1;
  if (nn > 0 && kk > 0) dsyrk_("L", "N", &nn, &kk, &sign, a, &la, &one, c, &lc, 1, 1);
}

// B := B L^T, L lower triangular (k x k, inside an array of leading dimension ldl), B n x k.
void multiply_by_transpose(Eigen::Index k, const double* lower, Eigen::Index ldl, Eigen::MatrixXd& b) {
  const int n = size_of(b.rows()), kk = size_of(k), ll = size_of(ldl);
  const double one = 1;
  if (n > 0 && kk > 0) dtrmm_("R", "L", "T", "N", &n, &kk, &one, lower, &ll, b.data(), &n, 1, 1, 1, 1);
}

// The lower triangle of L L^T for a lower triangular L (n x n): n^3 / 3 flops, where dsyrk, which
// takes L as full, spends n^3. LAPACK's dlauum forms U U^T for an upper triangular U: U is L with
// its rows and columns reversed, and so is the product.
Eigen::MatrixXd lower_times_transpose(const Eigen::Ref<const Eigen::MatrixXd>& lower) {
  const Eigen::Index n = lower.rows();
  Eigen::MatrixXd reversed = lower.reverse();
  const int nn = size_of(n);
  int info = 0;
  if (nn > 0) dlauum_("U", &nn, reversed.data(), &nn, &info, 1);
  if (info != 0) throw std::logic_error("dlauum: bad argument " + std::to_string(-info));
  return reversed.reverse();
}

}  // namespace
}  // namespace lapack

struct TrailingBlockCholesky::Cholmod {
  cholmod_common common;
  cholmod_factor* factor = nullptr;
  Cholmod() {
    cholmod_start(&common);
    // The order is ours (B last); CHOLMOD's postordering would move block columns that are not
    // ancestors of the rest in front of it.
    common.nmethods = 1;
    common.method[0].ordering = CHOLMOD_NATURAL;
    common.postorder = 0;
    common.supernodal = CHOLMOD_SUPERNODAL;
  }
  ~Cholmod() {
    if (factor) cholmod_free_factor(&factor, &common);
    cholmod_finish(&common);
  }
};

namespace {

// A dense result CHOLMOD allocated, freed on every path.
struct DenseResult {
  cholmod_dense* dense;
  cholmod_common* common;
  DenseResult(cholmod_dense* d, cholmod_common* c) : dense(d), common(c) {}
  ~DenseResult() {
    if (dense) cholmod_free_dense(&dense, common);
  }
  DenseResult(const DenseResult&) = delete;
  DenseResult& operator=(const DenseResult&) = delete;
  Eigen::Map<const Eigen::MatrixXd> matrix() const {
    return {static_cast<const double*>(dense->x), static_cast<Eigen::Index>(dense->nrow), static_cast<Eigen::Index>(dense->ncol)};
  }
};

}  // namespace

TrailingBlockCholesky::TrailingBlockCholesky() : cholmod_(std::make_unique<Cholmod>()) {}
TrailingBlockCholesky::~TrailingBlockCholesky() = default;

bool TrailingBlockCholesky::factorize_anchor(const Eigen::SparseMatrix<double>& K, std::span<const int> block, const std::vector<int>& ordering) {
  const auto t0 = std::chrono::steady_clock::now();
  auto& c = *cholmod_;
  // Whatever happens below, nothing of the previous anchor survives.
  if (c.factor) cholmod_free_factor(&c.factor, &c.common);
  kept_.clear();
  const Eigen::Index n = K.rows();
  if (static_cast<Eigen::Index>(ordering.size()) != n) throw std::invalid_argument("TrailingBlockCholesky: the ordering must have one entry per dof");
  std::vector<char> in_block(static_cast<std::size_t>(n), 0);
  for (int d : block) {
    if (d < 0 || d >= n || in_block[static_cast<std::size_t>(d)]) throw std::invalid_argument("TrailingBlockCholesky: block dofs must be distinct dofs of K");
    in_block[static_cast<std::size_t>(d)] = 1;
  }
  block_.assign(block.begin(), block.end());
  order_.clear();
  order_.reserve(static_cast<std::size_t>(n));
  for (int d : ordering)
    if (!in_block[static_cast<std::size_t>(d)]) order_.push_back(d);
  order_.insert(order_.end(), block_.begin(), block_.end());

  // Permuted here: CHOLMOD permuting from a given order made an anchor 10 % slower.
  Eigen::PermutationMatrix<Eigen::Dynamic, Eigen::Dynamic, int> position(n);
  for (Eigen::Index k = 0; k < n; ++k) position.indices()[order_[static_cast<std::size_t>(k)]] = static_cast<int>(k);
  Eigen::SparseMatrix<double> permuted(n, n);
  permuted.selfadjointView<Eigen::Lower>() = K.selfadjointView<Eigen::Lower>().twistedBy(position);
  cholmod_sparse A = Eigen::viewAsCholmod(permuted);
  A.stype = -1;

  c.factor = cholmod_analyze(&A, &c.common);
  if (!c.factor) {
    anchor_seconds_ += seconds_since(t0);
    return false;
  }
  cholmod_factorize(&A, c.factor, &c.common);
  if (c.common.status == CHOLMOD_NOT_POSDEF || c.factor->minor < c.factor->n) {
    cholmod_free_factor(&c.factor, &c.common);
    throw std::runtime_error("stiffness matrix is not positive definite: the part is not held against rigid motion");
  }
  if (c.common.status != CHOLMOD_OK || !c.factor->is_super) {
    cholmod_free_factor(&c.factor, &c.common);
    anchor_seconds_ += seconds_since(t0);
    return false;
  }
  const int* perm = static_cast<const int*>(c.factor->Perm);
  for (Eigen::Index k = 0; k < n; ++k)
    if (perm[k] != k) throw std::logic_error("TrailingBlockCholesky: CHOLMOD reordered the given order");

  // L_BB: the last m columns, read from the supernodes that hold them (each supernode's columns are
  // stored dense, column-major, over its row pattern).
  const Eigen::Index m = block_size(), first = n - m;
  lower_bb_ = Eigen::MatrixXd::Zero(m, m);
  const int* super = static_cast<const int*>(c.factor->super);
  const int* pi = static_cast<const int*>(c.factor->pi);
  const int* px = static_cast<const int*>(c.factor->px);
  const int* rows = static_cast<const int*>(c.factor->s);
  const double* x = static_cast<const double*>(c.factor->x);
  for (std::size_t s = 0; s < c.factor->nsuper; ++s) {
    const int c0 = super[s], c1 = super[s + 1], height = pi[s + 1] - pi[s];
    for (int col = std::max(c0, static_cast<int>(first)); col < c1; ++col)
      for (int r = col - c0; r < height; ++r)
        lower_bb_(rows[pi[s] + r] - first, col - first) = x[px[s] + static_cast<std::ptrdiff_t>(col - c0) * height + r];
  }
  reset_to_anchor();
  anchor_seconds_ += seconds_since(t0);
  return true;
}

void TrailingBlockCholesky::reset_to_anchor() {
  schur_is_anchor_ = true;
  schur_factor_.resize(0, 0);
  trailing_.resize(0, 0);
  trailing_start_ = 0;
}

bool TrailingBlockCholesky::refactorize_trailing(Eigen::Index first, const std::function<void(Eigen::Ref<Eigen::MatrixXd>)>& change) {
  const Eigen::Index m = block_size();
  if (!cholmod_->factor) throw std::logic_error("TrailingBlockCholesky::refactorize_trailing before factorize_anchor");
  if (first < 0 || first > m) throw std::invalid_argument("TrailingBlockCholesky: the changed part must start inside the block");
  const auto t0 = std::chrono::steady_clock::now();
  const Eigen::Index t = m - first;
  const Eigen::MatrixXd& factor = schur_is_anchor_ ? lower_bb_ : schur_factor_;
  // T = S_22 - L_21 L_21^T = L_22 L_22^T, formed from the last T (T_q, from block index q; none at
  // the anchor: q = m), so that the cost follows how far `first` moved since, not t.
  const Eigen::Index q = schur_is_anchor_ ? m : trailing_start_;
  Eigen::MatrixXd T(t, t);
  if (first >= q) {
    // Moved on by k: T_q minus the k columns that left (t^2 k), or L_22 L_22^T if that is less (t^3 / 3).
    const Eigen::Index k = first - q;
    if (3 * k <= t) {
      T = trailing_.bottomRightCorner(t, t);
      lapack::add_product(-1, t, k, factor.data() + first + q * m, m, T.data(), t);
    } else {
      T = lapack::lower_times_transpose(factor.bottomRightCorner(t, t));
    }
  } else {
    // Moved back by k: with L's rows from `first` on split at q into [A 0; B C] (C C^T = T_q),
    // T = [A A^T, .; B A^T, B B^T + T_q]: L_22 L_22^T less the (t - k)^3 / 3 of C C^T.
    const Eigen::Index k = q - first, rest = m - q;
    const double* a = factor.data() + first + first * m;
    const double* b = factor.data() + q + first * m;
    T.topLeftCorner(k, k) = lapack::lower_times_transpose(factor.block(first, first, k, k));
    if (rest > 0) {
      T.bottomRightCorner(rest, rest) = trailing_;
      lapack::add_product(+1, rest, k, b, m, T.data() + k + k * t, t);
      Eigen::MatrixXd ba = factor.block(q, first, rest, k);
      lapack::multiply_by_transpose(k, a, m, ba);
      T.bottomLeftCorner(rest, k) = ba;
    }
  }
  change(T);
  Eigen::MatrixXd refactorized = T;
  const bool positive = lapack::cholesky_lower(refactorized);
  if (positive) {
    if (schur_is_anchor_) schur_factor_ = lower_bb_;
    schur_factor_.bottomRightCorner(t, t) = refactorized;
    trailing_ = std::move(T);
    trailing_start_ = first;
    schur_is_anchor_ = false;
    trailing_dofs_ += t;
  }
  refactorize_seconds_ += seconds_since(t0);
  return positive;
}

Eigen::MatrixXd TrailingBlockCholesky::solve(const Eigen::MatrixXd& rhs) {
  auto& c = *cholmod_;
  if (!c.factor) throw std::logic_error("TrailingBlockCholesky::solve before factorize_anchor");
  const auto t0 = std::chrono::steady_clock::now();
  const Eigen::Index n = rhs.rows(), m = block_size(), first = n - m;
  // With f = [f_R; f_B]:  y = L_RR^-1 f_R,  x_B = S^-1 (f_B - L_BR y),  x_R = L_RR^-T (y - L_BR^T x_B).
  // A forward solve of [f_R; 0] with the whole L gives [y; -L_BB^-1 L_BR y], so L_BR y = -L_BB (its
  // B part); a backward solve of [y; L_BB^T x_B] gives [x_R; x_B].
  // Within a run of stations f_R rarely changes (removed material loads only its own dofs): the
  // forward solve of the last f_R is kept and reused while f_R is bit for bit the same.
  Eigen::MatrixXd f_r(first, rhs.cols());
  for (Eigen::Index k = 0; k < first; ++k) f_r.row(k) = rhs.row(order_[static_cast<std::size_t>(k)]);
  auto kept = std::find_if(kept_.begin(), kept_.end(), [&](const KeptForward& k) { return k.f_r.cols() == f_r.cols() && k.f_r == f_r; });
  if (kept == kept_.end()) {
    Eigen::MatrixXd b(n, rhs.cols());
    b.topRows(first) = f_r;
    b.bottomRows(m).setZero();
    cholmod_dense forward_in = Eigen::viewAsCholmod(b);
    const DenseResult forward(cholmod_solve(CHOLMOD_L, c.factor, &forward_in, &c.common), &c.common);
    if (!forward.dense) throw std::runtime_error("CHOLMOD: the forward solve failed");
    if (kept_.size() == 4) kept_.erase(kept_.begin());  // one per profile group, in practice
    Eigen::MatrixXd coupling = forward.matrix().bottomRows(m);
    lapack::triangular_multiply(lower_bb_, false, coupling.cols(), coupling.data(), m);
    kept_.push_back({std::move(f_r), forward.matrix(), std::move(coupling)});
    kept = std::prev(kept_.end());
    ++forward_solves_;
  }
  Eigen::MatrixXd y = kept->forward;
  Eigen::MatrixXd f_b(m, rhs.cols());
  for (Eigen::Index k = 0; k < m; ++k) f_b.row(k) = rhs.row(block_[static_cast<std::size_t>(k)]);
  f_b += kept->coupling;
  Eigen::MatrixXd x_b;
  if (schur_is_anchor_) {
    // S is the anchor's, L_BB L_BB^T: the backward solve below finishes x_B itself.
    lapack::triangular_solve(lower_bb_, f_b.cols(), f_b.data(), m);
    y.bottomRows(m) = f_b;
  } else {
    x_b = f_b;
    lapack::cholesky_solve(schur_factor_, x_b);
    y.bottomRows(m) = x_b;
    lapack::triangular_multiply(lower_bb_, true, y.cols(), y.data() + first, n);
  }
  cholmod_dense backward_in = Eigen::viewAsCholmod(y);
  const DenseResult backward(cholmod_solve(CHOLMOD_Lt, c.factor, &backward_in, &c.common), &c.common);
  if (!backward.dense) throw std::runtime_error("CHOLMOD: the backward solve failed");
  const auto z = backward.matrix();
  Eigen::MatrixXd x(n, rhs.cols());
  for (Eigen::Index k = 0; k < first; ++k) x.row(order_[static_cast<std::size_t>(k)]) = z.row(k);
  // x_B as the dense solve gave it (the backward solve only gives it back through L_BB^-T L_BB^T).
  if (schur_is_anchor_) x_b = z.bottomRows(m);
  for (Eigen::Index k = 0; k < m; ++k) x.row(block_[static_cast<std::size_t>(k)]) = x_b.row(k);
  solve_seconds_ += seconds_since(t0);
  return x;
}

}  // namespace drom::fem
