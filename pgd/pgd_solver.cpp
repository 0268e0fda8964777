#include "pgd/pgd_solver.hpp"

#include "support/kernel_threads.hpp"
#include "support/resources.hpp"

#include <Eigen/Dense>
#include <kinsol/kinsol.h>
#include <nvector/nvector_serial.h>
#include <sundials/sundials_context.h>

#include <chrono>
#include <cmath>
#include <limits>
#include <optional>
#include <stdexcept>

namespace drom::pgd {

namespace {

std::array<Eigen::VectorXd, 3> split(const Eigen::VectorXd& v, Eigen::Index n) { return {v.segment(0, n), v.segment(n, n), v.segment(2 * n, n)}; }

// What KINSOL's fixed-point function needs: the map S -> G(S) normalized by a fixed linear form, so
// that the iteration converges to one representative of the product's scaling freedom.
struct FixedPointContext {
  PgdSolver* solver;
  const ComponentTensors* residual;
  Eigen::VectorXd normal;  // the normalization functional: normal . S = 1
  std::array<Eigen::VectorXd, 3> R;
  int evaluations = 0;
};

int fixed_point_map(N_Vector s, N_Vector g, void* data) {
  auto* ctx = static_cast<FixedPointContext*>(data);
  const auto n = static_cast<Eigen::Index>(N_VGetLength_Serial(s));
  Eigen::Map<const Eigen::VectorXd> S(N_VGetArrayPointer_Serial(s), n);
  Eigen::Map<Eigen::VectorXd> G(N_VGetArrayPointer_Serial(g), n);
  Eigen::VectorXd next;
  try {
    ctx->solver->alternate(*ctx->residual, S, next, ctx->R);
  } catch (...) {
    return -1;
  }
  ++ctx->evaluations;
  const double scale = ctx->normal.dot(next);
  if (!(std::abs(scale) > 1e-12 * next.norm())) return 1;  // the product left the normalization's reach: recoverable
  G = next / scale;
  return 0;
}

struct SundialsContext {
  SUNContext ctx = nullptr;
  SundialsContext() {
    if (SUNContext_Create(nullptr, &ctx) != 0) throw std::runtime_error("SUNDIALS: cannot create a context");
  }
  ~SundialsContext() { SUNContext_Free(&ctx); }
};

// Serial N_Vector owned for the scope (freed on every exit, exceptions included).
struct SerialVector {
  N_Vector v;
  SerialVector(sunindextype n, SUNContext ctx) : v(N_VNew_Serial(n, ctx)) {
    if (!v) throw std::runtime_error("SUNDIALS: cannot allocate a vector");
  }
  ~SerialVector() { N_VDestroy(v); }
  SerialVector(const SerialVector&) = delete;
  SerialVector& operator=(const SerialVector&) = delete;
  Eigen::Map<Eigen::VectorXd> values() { return {N_VGetArrayPointer_Serial(v), static_cast<Eigen::Index>(N_VGetLength_Serial(v))}; }
};

}  // namespace

PgdSolver::PgdSolver(SeparatedOperator& op, PgdSettings settings) : op_(op), settings_(settings), plane_solver_(true), update_solver_(true) {}

void PgdSolver::factorize(fem::SpdSolver& solver, const Eigen::SparseMatrix<double>& K) {
  ++factorizations_;
  try {
    solver.factorize(K);
  } catch (const std::runtime_error&) {
    // A function living almost only in removed material has ~1e-9 of the stiffness while a clamp's
    // penalty has 1e8: round-off can make such a 2D sub-problem indefinite. A shift of 1e-12 of the
    // largest diagonal makes it definite; the residual and the stopping tests still use the true
    // operator, so only the sub-problem's answer moves, not what the solver accepts.
    Eigen::SparseMatrix<double> shifted = K;
    const double largest = shifted.diagonal().maxCoeff();
    for (Eigen::Index c = 0; c < shifted.cols(); ++c) shifted.coeffRef(c, c) += 1e-12 * largest;
    solver.factorize(shifted);
    ++regularized_;
  }
  factor_flops_ += solver.stats().factor_flops;
  if (&solver == &update_solver_) update_factor_flops_ += solver.stats().factor_flops;
}

std::array<Eigen::VectorXd, 3> PgdSolver::plane_functions(const ComponentTensors& r, const Eigen::VectorXd& S_in) {
  // The 2D problem with S fixed; its right-hand side is the residual projected on S.
  const auto S = split(S_in, op_.grid().thickness_nodes());
  const std::array<Eigen::MatrixXd, 3> Z{S[0], S[1], S[2]};
  const auto t0 = std::chrono::steady_clock::now();
  factorize(plane_solver_, op_.plane_matrix(Z));
  const auto X = op_.plane_functions(plane_solver_.solve(op_.plane_load(r, Z)), Z);
  plane_seconds_ += seconds_since(t0);
  return {X[0].col(0), X[1].col(0), X[2].col(0)};
}

void PgdSolver::alternate(const ComponentTensors& r, const Eigen::VectorXd& S_in, Eigen::VectorXd& S_out, std::array<Eigen::VectorXd, 3>& R) {
  const Eigen::Index nz = op_.grid().thickness_nodes();
  R = plane_functions(r, S_in);
  // S: the 1D problem with R fixed.
  Eigen::VectorXd rhs_z(3 * nz);
  for (int i = 0; i < 3; ++i) rhs_z.segment(i * nz, nz).noalias() = r[static_cast<std::size_t>(i)].transpose() * R[static_cast<std::size_t>(i)];
  S_out = op_.thickness_matrix(R).ldlt().solve(rhs_z);
}

bool PgdSolver::update_plane_functions(const ComponentTensors& F, SeparatedField& u, ComponentTensors& r) {
  if (settings_.max_update_functions <= 0) return false;
  SeparatedField basis = u;
  basis.compress(settings_.compression_tolerance);  // orthonormal thickness functions
  const int functions = basis.terms(0) + basis.terms(1) + basis.terms(2);
  if (functions == 0 || functions > settings_.max_update_functions) return false;
  const auto t0 = std::chrono::steady_clock::now();
  std::optional<BlasThreads> threads;
  if (settings_.update_threads > 1) threads.emplace(settings_.update_threads);
  factorize(update_solver_, op_.plane_matrix(basis.Z));
  basis.X = op_.plane_functions(update_solver_.solve(op_.plane_load(F, basis.Z)), basis.Z);
  plane_seconds_ += seconds_since(t0);
  update_seconds_ += seconds_since(t0);
  r = F;
  op_.subtract_product(basis, r);
  u = std::move(basis);
  ++updates_;
  return true;
}

SeparatedField PgdSolver::solve(const ComponentTensors& F, const SeparatedField* warm_start, PgdReport& report) {
  const auto start = std::chrono::steady_clock::now();
  plane_seconds_ = 0;
  updates_ = 0;
  update_seconds_ = 0;
  factorizations_ = 0;
  regularized_ = 0;
  factor_flops_ = update_factor_flops_ = 0;
  report = PgdReport{};
  const auto& grid = op_.grid();
  const Eigen::Index nz = grid.thickness_nodes();
  SeparatedField u = SeparatedField::empty(grid);
  ComponentTensors r = F;
  report.load_norm = op_.free_norm(F);
  if (report.load_norm == 0) {
    report.converged = true;
    report.initial_ratio = report.final_ratio = 0;
    return u;
  }

  // 1. Warm start: the previous solution (its terms above warm_start_truncation) as it stands; the
  //    update after the first new mode re-solves all its plane functions with the new thickness shape.
  if (warm_start && warm_start->max_terms() > 0) {
    u = *warm_start;
    u.compress(settings_.warm_start_truncation);
    report.warm_start_terms = u.terms(0) + u.terms(1) + u.terms(2);
    op_.subtract_product(u, r);
  }
  double ratio = op_.free_norm(r) / report.load_norm;
  report.initial_ratio = ratio;
  // The second stopping test: how much the last enrichment cycle (modes + update) changed the field,
  // in energy norm (blind to the rigid motion a free part's weak foundation leaves loosely set).
  // D.12 alone can stop too early: thin parts are flexible, so a small out-of-balance force can still
  // mean a sizeable displacement (measured: a warm start at ratio 1e-3 was 1e-2 off in displacement).
  SeparatedField last = u;
  double increment = std::numeric_limits<double>::infinity();
  const int every = std::max(1, settings_.update_every);
  int since_update = report.warm_start_terms > 0 ? every - 1 : 0;  // after a warm start, update at the first mode

  // 2. Enrichment.
  SundialsContext sundials;
  const auto n = static_cast<sunindextype>(3 * nz);
  SerialVector s_vec(n, sundials.ctx), scale(n, sundials.ctx);
  N_VConst(1.0, scale.v);
  FixedPointContext ctx{this, &r, {}, {}, 0};
  while ((ratio > settings_.residual_tolerance || increment > settings_.increment_tolerance) && report.modes_added < settings_.max_modes) {
    // Initial S: one power step on the residual, a cheap guess at its dominant thickness shape.
    Eigen::VectorXd S0(3 * nz);
    for (int i = 0; i < 3; ++i) {
      const auto& ri = r[static_cast<std::size_t>(i)];
      Eigen::VectorXd s = ri.transpose() * (ri * Eigen::VectorXd::Ones(nz));
      S0.segment(i * nz, nz) = s;
    }
    if (S0.norm() == 0) S0.setOnes();
    S0 /= S0.norm();
    ctx.normal = S0;
    ctx.evaluations = 0;
    s_vec.values() = S0;

    void* kin = KINCreate(sundials.ctx);
    if (!kin) throw std::runtime_error("KINSOL: cannot create a solver");
    KINSetMAA(kin, settings_.anderson_depth);
    KINInit(kin, fixed_point_map, s_vec.v);
    KINSetUserData(kin, &ctx);
    KINSetFuncNormTol(kin, settings_.fixed_point_tolerance);
    KINSetNumMaxIters(kin, settings_.max_fixed_point_iterations);
    KINSetPrintLevel(kin, 0);
    KINSetErrHandlerFn(kin, [](int, const char*, const char*, char*, void*) {}, nullptr);  // flags are handled below
    const int flag = KINSol(kin, s_vec.v, KIN_FP, scale.v, scale.v);
    KINFree(&kin);
    if (flag < 0 && flag != KIN_MAXITER_REACHED) throw std::runtime_error("PGD fixed point failed (KINSOL flag " + std::to_string(flag) + ")");
    if (flag == KIN_MAXITER_REACHED) ++report.unconverged_modes;
    report.fixed_point_iterations += ctx.evaluations;
    report.mode_iterations.push_back(ctx.evaluations);

    // The mode: R from the converged S (Anderson mixes iterates, so the last evaluation's R belongs to
    // another S; one more 2D solve makes R the Galerkin partner of S).
    const Eigen::VectorXd S = s_vec.values();
    ctx.R = plane_functions(r, S);
    SeparatedField mode = SeparatedField::empty(grid);
    const auto Sc = split(S, nz);
    for (int i = 0; i < 3; ++i)
      if (ctx.R[static_cast<std::size_t>(i)].squaredNorm() > 0 && Sc[static_cast<std::size_t>(i)].squaredNorm() > 0)
        mode.append(i, ctx.R[static_cast<std::size_t>(i)], Sc[static_cast<std::size_t>(i)]);
    // Work of the residual on the new mode: with R the 2D Galerkin solution for S, the potential energy
    // changes by -work / 2, so the energy decreases with every mode even where |r| does not.
    double work = 0;
    for (std::size_t i = 0; i < 3; ++i) work += ctx.R[i].dot(r[i] * Sc[i]);
    report.energy_decrease.push_back(0.5 * work);
    u.append(mode);
    ++report.modes_added;
    const bool due = ++since_update >= every;
    if (due && update_plane_functions(F, u, r)) {
      since_update = 0;
      SeparatedField change = u;
      change.append(last, -1.0);
      increment = op_.energy_norm(change) / std::max(1e-300, op_.energy_norm(u));
      last = u;
    } else {
      op_.subtract_product(mode, r);
      // Past the update's size cap the modes are all there is: their own size is the change.
      increment = due ? op_.energy_norm(mode) / std::max(1e-300, op_.energy_norm(u)) : std::numeric_limits<double>::infinity();
    }
    report.increment.push_back(increment);
    const double next_ratio = op_.free_norm(r) / report.load_norm;
    report.residual_ratio.push_back(next_ratio);
    if (!std::isfinite(next_ratio)) throw std::runtime_error("PGD enrichment produced a non-finite residual");
    ratio = next_ratio;
  }

  // Stopped by the mode cap after modes the last update did not see: one more update.
  if (since_update > 0 && ratio > settings_.residual_tolerance && update_plane_functions(F, u, r)) ratio = op_.free_norm(r) / report.load_norm;
  u.compress(settings_.compression_tolerance);
  report.final_ratio = ratio;
  report.final_increment = increment;
  report.converged = ratio <= settings_.residual_tolerance && increment <= settings_.increment_tolerance;
  report.seconds = seconds_since(start);
  report.plane_solve_seconds = plane_seconds_;
  report.plane_factorizations = factorizations_;
  report.regularized_factorizations = regularized_;
  report.factor_flops = factor_flops_;
  report.update_factor_flops = update_factor_flops_;
  report.updates = updates_;
  report.update_seconds = update_seconds_;
  return u;
}

}  // namespace drom::pgd
