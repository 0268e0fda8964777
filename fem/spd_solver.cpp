#include "fem/spd_solver.hpp"

#include "support/resources.hpp"

#include <Eigen/CholmodSupport>

#include <chrono>
#include <mutex>
#include <stdexcept>

namespace drom::fem {

struct SpdSolver::Impl {
  Eigen::CholmodSupernodalLLT<Eigen::SparseMatrix<double>, Eigen::Lower> llt;
  bool analyzed = false;
  Eigen::Index size = -1;
};

SpdSolver::SpdSolver(bool keep_order) : impl_(std::make_unique<Impl>()) {
  if (keep_order) {
    auto& common = impl_->llt.cholmod();
    common.nmethods = 1;
    common.method[0].ordering = CHOLMOD_NATURAL;
  }
}

namespace {
// METIS's random generator is process-global: two analyses at once interleave it and get different
// orderings (and different round-off). Every analysis that may run METIS takes this lock.
std::mutex& metis_lock() {
  static std::mutex lock;
  return lock;
}
}  // namespace

std::vector<int> fill_reducing_ordering(Eigen::SparseMatrix<double> lower, double* flops) {
  std::lock_guard<std::mutex> lock(metis_lock());
  cholmod_common common;
  cholmod_start(&common);
  cholmod_sparse A = Eigen::viewAsCholmod(lower);  // CHOLMOD's view needs a mutable matrix: taken by value
  A.stype = -1;  // the lower triangle of a symmetric matrix
  cholmod_factor* L = cholmod_analyze(&A, &common);
  if (!L) {
    cholmod_finish(&common);
    throw std::runtime_error("CHOLMOD: cannot order the pattern");
  }
  const int* perm = static_cast<const int*>(L->Perm);
  std::vector<int> ordering(perm, perm + lower.rows());
  if (flops) *flops = common.fl;
  cholmod_free_factor(&L, &common);
  cholmod_finish(&common);
  return ordering;
}
SpdSolver::~SpdSolver() = default;
SpdSolver::SpdSolver(SpdSolver&&) noexcept = default;
SpdSolver& SpdSolver::operator=(SpdSolver&&) noexcept = default;

void SpdSolver::factorize(const Eigen::SparseMatrix<double>& K) {
  if (!impl_->analyzed || impl_->size != K.rows()) {
    // One analysis at a time (metis_lock); each reseeds, so every solver of the same pattern gets
    // the same ordering.
    std::lock_guard<std::mutex> lock(metis_lock());
    const auto t0 = std::chrono::steady_clock::now();
    impl_->llt.analyzePattern(K);
    impl_->analyzed = true;
    impl_->size = K.rows();
    stats_.analyze_seconds += seconds_since(t0);
    stats_.factor_flops = impl_->llt.cholmod().fl;
    stats_.factor_nonzeros = impl_->llt.cholmod().lnz;
  }
  const auto t0 = std::chrono::steady_clock::now();
  impl_->llt.factorize(K);
  stats_.factorize_seconds += seconds_since(t0);
  ++stats_.factorizations;
  stats_.factor_peak_bytes = std::max(stats_.factor_peak_bytes, impl_->llt.cholmod().memory_usage);
  if (impl_->llt.info() != Eigen::Success)
    throw std::runtime_error("stiffness matrix is not positive definite: the part is not held against rigid motion");
}

Eigen::MatrixXd SpdSolver::solve(const Eigen::MatrixXd& rhs) {
  const auto t0 = std::chrono::steady_clock::now();
  Eigen::MatrixXd x = impl_->llt.solve(rhs);
  stats_.solve_seconds += seconds_since(t0);
  return x;
}

}  // namespace drom::fem
