#pragma once
// Greedy PGD solution of K u = F on a SeparatedOperator (docs/design.md §4, seed Annex D):
//   u_n = u_0 + sum_q R_q(u, v) S_q(t), one product at a time; each product by the alternating
//   fixed point  S -> R (2D problem, S fixed) -> S (1D problem, R fixed), accelerated by SUNDIALS
//   KINSOL's Anderson mixing (depth 0 = the plain fixed point of the seed);
//   stop when |r_n| / |r_0| < residual_tolerance (eq. D.12) and the last cycle changed the field by less
//   than increment_tolerance, or at max_modes.
// The residual r = F - K u is kept as one full-size tensor per component: projections onto S or R
// are then matrix-vector products, and eq. D.12 is evaluated exactly, at a cost linear in the number
// of thickness nodes (nothing plane x thickness is ever factorized).
// Update: after each mode, all plane functions are solved again on the span of the thickness functions
// found so far (one coupled 2D problem), so a mode only has to bring a new thickness shape; the
// fields of thin parts have few of them (measured: 5-6 per component to 1e-5 on a machined plate).
// Warm start: the previous solution (its terms above warm_start_truncation) is the starting field; the
// update after the first new mode re-solves all its plane functions with the new thickness shape.
#include "fem/spd_solver.hpp"
#include "pgd/separated_field.hpp"
#include "pgd/separated_operator.hpp"

#include <vector>

namespace drom::pgd {

struct PgdSettings {
  // eq. D.12 ...
  double residual_tolerance = 1e-2;
  // ... and the last enrichment cycle (modes since the previous update, and the update) changed the
  // field by less than this, relative, in energy norm. Both at 1e-2, measured on the bench plate
  // against 3D FE on the same mesh: max displacement difference 4.5e-7 (20 x 20 x 20) and 2.6e-6
  // (40 x 40 x 20), in 9 and 12 modes; at 1e-3 the same runs took 12 and 15 modes (at 20 x 20: 6.7 s
  // against 3.2 s) for 8.7e-7 and 2.6e-6. The energy norm weighs the local 3D stress at the pocket's
  // edges, which the displacement barely feels.
  double increment_tolerance = 1e-2;
  double fixed_point_tolerance = 1e-3;
  int max_modes = 80;
  int max_fixed_point_iterations = 20;
  int anderson_depth = 3;
  // After each mode, every plane function is solved again at once: the Galerkin solution on (any plane
  // functions) x (the thickness functions found so far), while they number at most this many over the
  // three components; 0 turns the update off (pure greedy).
  // Its cost grows as the cube of that number, so it runs every update_every modes (measured on the
  // bench plate at N_z = 20: every mode 23 s, every 3rd 7.6 s, same 14 modes). Truncating its basis
  // (dropping thickness functions whose terms are small) stalled the residual: kept whole.
  int max_update_functions = 45;
  int update_every = 3;
  // A warm start keeps the previous terms above this (relative singular value): each station's mode
  // adds thickness functions, and without a cut the update's size would grow station after station
  // (measured, 10 x 10 x 20 plate: F 36 -> 48 in four stations, then past the update's cap; a cut at
  // 1e-4 or 1e-6 dropped functions the next station needed again).
  double warm_start_truncation = 1e-8;
  // OpenBLAS threads for the update's factorization, whose dense node blocks (F x F per plane node)
  // are large enough for threads to pay. The thread count is process-wide: leave 1 wherever several
  // solves run at once (station workers); a lone solve may use the machine's cores.
  int update_threads = 1;
  // Terms of the returned field whose singular value is below this (relative) are dropped.
  double compression_tolerance = 1e-12;
};

struct PgdReport {
  int modes_added = 0;
  int fixed_point_iterations = 0;  // 2D + 1D solve pairs, over all modes
  int unconverged_modes = 0;       // fixed points stopped by max_fixed_point_iterations
  int warm_start_terms = 0;
  double load_norm = 0;
  double initial_ratio = 1;                // |F - K u_0| / |F| after the warm start
  std::vector<double> residual_ratio;      // after each added mode
  std::vector<int> mode_iterations;        // fixed-point iterations of each added mode
  std::vector<double> increment;           // relative change of the field at each mode (inf between updates)
  std::vector<double> energy_decrease;     // potential energy drop brought by each mode (N mm)
  double final_ratio = 1, final_increment = 0;
  bool converged = false;
  int updates = 0;                   // plane-function updates
  double update_seconds = 0;         // of which in the updates (included in plane_solve_seconds)
  int plane_factorizations = 0;      // 2D Cholesky factorizations (modes and updates)
  int regularized_factorizations = 0;  // of which needed a 1e-12 diagonal shift to be definite
  // Floating-point work of those factorizations (CHOLMOD's count), all and the updates' alone: the
  // figure to set against a 3D factorization's (fem::SolverStats::factor_flops).
  double factor_flops = 0, update_factor_flops = 0;
  double seconds = 0, plane_solve_seconds = 0;
};

class PgdSolver {
 public:
  PgdSolver(SeparatedOperator& op, PgdSettings settings);
  // Solves K u = F. `warm_start` (may be null or empty) seeds the basis.
  SeparatedField solve(const ComponentTensors& F, const SeparatedField* warm_start, PgdReport& report);
  const fem::SolverStats& plane_solver_stats() const { return plane_solver_.stats(); }

  // The plane functions R that solve the 2D problem for thickness functions S, on residual r.
  std::array<Eigen::VectorXd, 3> plane_functions(const ComponentTensors& r, const Eigen::VectorXd& S);
  // One alternating step on residual r: R from S (2D solve), then S from R (1D solve).
  void alternate(const ComponentTensors& r, const Eigen::VectorXd& S_in, Eigen::VectorXd& S_out, std::array<Eigen::VectorXd, 3>& R);

 private:
  bool update_plane_functions(const ComponentTensors& F, SeparatedField& u, ComponentTensors& r);
  SeparatedOperator& op_;
  PgdSettings settings_;
  fem::SpdSolver plane_solver_, update_solver_;  // the mode's 3-function problem; the update's
  int updates_ = 0;
  double update_seconds_ = 0;
  double plane_seconds_ = 0;
  int factorizations_ = 0, regularized_ = 0;
  double factor_flops_ = 0, update_factor_flops_ = 0;
  void factorize(fem::SpdSolver& solver, const Eigen::SparseMatrix<double>& K);
};

}  // namespace drom::pgd
