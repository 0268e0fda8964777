#pragma once
// The full-order problem of docs/design.md §1 and §3, in the deal.II style: one class, with
// setup (mesh, part, material, stress profiles), equilibrate, configure (activity, supports),
// assemble_and_factorize, solve.
//
//   find u on the remaining part, u = 0 on the supports:
//     int eps(v) : C : eps(u) = - int eps(v) : sigma0        for every admissible v
//   sigma0 = sigma_R + C : eps(u0), u0 the free stock's response to sigma_R (3-2-1 held).
//
// Every profile (one per column) is solved on one factorization.
#include "fem/element_operators.hpp"
#include "fem/mesh.hpp"
#include "geometry/part_shape.hpp"
#include "fem/residual_stress.hpp"
#include "fem/spd_solver.hpp"
#include "fem/stiffness_pattern.hpp"
#include "fem/trailing_block_cholesky.hpp"

#include <Eigen/Core>
#include <Eigen/SparseCore>

#include <memory>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

namespace drom::fem {

// What the block refactorization (assemble_and_factorize_anchor / refactorize_changed) did.
struct BlockStats {
  int anchors = 0;               // factorizations with a block eliminated last (blocks that paid)
  int anchors_by_first_change = 0;  // of which the block was ordered by first change (BlockPlan)
  int block_refactorizations = 0;  // stations that refactorized only their block (its trailing part)
  int unchanged_stations = 0;    // later stations of a run that changed nothing since the last: nothing refactorized
  int full_chunks = 0;           // anchors whose block was too large to pay: factorized in full instead
  int residual_fallbacks = 0;    // group solves whose residual failed the bound: solved again in full
  int whole_residuals = 0;       // block solves checked on every row (the others: on the block's rows)
  long long block_dofs = 0;      // summed over anchors
  long long trailing_dofs = 0;   // refactorized, summed over block refactorizations
  double anchor_seconds = 0, refactorize_seconds = 0, solve_seconds = 0;
  double residual_seconds = 0;   // of the residual checks, and of the full solves' when measured
  double worst_residual = 0;     // of the block solves that were kept
  double worst_full_residual = 0;  // of the full solves, when measured (measure_full_residuals)
};

// What a run of stations changes after its first (station 0 of the run): per element, the first and
// the last station of the run that change it, 0 if none does.
struct RunChanges {
  std::vector<int> first, last;
  int stations = 1;  // the run's length, its first station included
};

// The block of a run of stations (ElasticProblem::assemble_and_factorize_anchor) and what its
// refactorizations are expected to cost.
struct BlockPlan {
  // The dofs of the elements the run's later stations change, in elimination order. At station j
  // only the trailing part of S's factor, from the first dof changed at j, is refactorized; of two
  // orders, the one whose estimated flops are fewer:
  //   by the last station that changes them (station j's trailing part: at most the dofs changed at
  //   j or later);
  //   by the first, latest first (by_first_change; at most the dofs first changed at j or before).
  // A node's three dofs are consecutive.
  std::vector<int> dofs;
  bool by_first_change = false;
  int stations = 1;      // the run's stations up to its last change (the anchor is station 0)
  int run_stations = 1;  // the run's length (RunChanges::stations), at least `stations`
  // Dense flops of stations 1 .. stations - 1: t^3 / 3 to refactorize the t trailing dofs (the
  // bounds above), plus forming their T (TrailingBlockCholesky::refactorize_trailing).
  double refactorization_flops = 0;
};

class ElasticProblem {
 public:
  // Elements whose remaining volume fraction is below this count as removed: a sliver of material
  // carries no load worth the ill-conditioning it brings.
  static constexpr double kMinVolumeFraction = 1e-3;

  ElasticProblem(const Mesh& mesh, const PartShape& shape, const Material& material, std::vector<StressProfile> profiles);

  // Step 1: equilibrate each profile on the intact free stock (held 3-2-1 at `isostatic_dofs`).
  void equilibrate(const std::vector<int>& isostatic_dofs);
  // Or take the equilibrium another problem on the same mesh, part and profiles computed (so parallel
  // workers share one equilibration), and its profile groups; and its fill-reducing ordering, if it
  // has one (full_factorization_flops).
  void adopt_equilibrium(const ElasticProblem& other);
  // The equilibrium (u0, r0, its residual, the profile groups) as bytes, and adopted from them: what
  // rank 0 of an MPI job hands the other ranks (offline/job_team.hpp), bit for bit. The bytes must
  // come from a problem on the same mesh and profiles (checked by size: std::invalid_argument).
  std::string equilibrium_bytes() const;
  void adopt_equilibrium(std::string_view bytes);
  // Before equilibrate: the profiles in consecutive groups of these sizes (default: one group), each
  // loaded and solved on its own, so that a group's columns are bit for bit those of a problem
  // holding that group alone (the quadrature follows a group's highest degree, and a triangular solve
  // rounds per block of right-hand sides). Two runs can then share one factorization per station.
  void set_profile_groups(std::vector<int> sizes);
  // Step 2: which material is left (per element, in [0, 1]) and which dofs are fixed.
  void set_activity(std::vector<double> volume_fraction);
  void set_fixed_dofs(std::vector<int> dofs);
  // Step 3.
  void assemble_and_factorize();
  // Step 3 for the first of a run of stations whose later changes stay inside the elements `changes`
  // names: factorizes this state with those elements' dofs eliminated last, in plan_block's order
  // (fem/trailing_block_cholesky.hpp), so that each later station of the run only refactorizes that
  // block's trailing part (refactorize_changed). When the block does not pay (block_pays), factorizes
  // in full instead, and the run's stations do too.
  void assemble_and_factorize_anchor(const RunChanges& changes);
  static BlockPlan plan_block(const Mesh& mesh, const RunChanges& changes);
  // Whether a run's block pays against a full factorization of `full_flops` at each of its
  // run_stations: its anchor (F + m^3 / 3) and refactorizations cost fewer flops, and m <= 4 000
  // (the dense matrices a worker keeps: 128 MB each). A run that changes nothing pays (m = 0: its
  // later stations factorize nothing) if it has more than one station.
  static bool block_pays(const BlockPlan& plan, double full_flops);
  // The flops of a full factorization of this problem's stiffness pattern in the fill-reducing order
  // the anchors use (one symbolic analysis, kept).
  double full_factorization_flops();
  // Step 3 for a later station of that run. The activity may differ from the anchor's only on the
  // changing elements (std::logic_error otherwise). Refactorizes S from the first block dof the
  // changes since the last factorization touch. Without an anchor: assemble_and_factorize().
  void refactorize_changed();
  // A block solve whose relative residual max_p ||K u_p - f_p|| / ||f_p|| over a profile group
  // exceeds this is thrown away: the station is factorized in full and that group solved again
  // (the run's next stations still try the block, with S rebuilt from the anchor's). Every block
  // solve is checked on the block's rows, where S's updates act; every kWholeResidualEvery-th of a
  // run, from its anchor, on every row. The rest's rows (R) solve K_RR x_R + K_RB x_B = f_R
  // through the anchor's own factor whatever S is: their residual is that factor's round-off.
  static constexpr int kWholeResidualEvery = 4;
  void set_residual_bound(double bound) { residual_bound_ = bound; }
  const BlockStats& block_stats() const { return block_stats_; }
  // Also measure the residual of full solves (one more sparse product each), for comparison.
  void measure_full_residuals(bool on) { measure_full_residual_ = on; }
  // Step 4: displacement since the equilibrated, clamped stock; ndof x profiles. Held dofs are zero.
  Eigen::MatrixXd solve();

  const Mesh& mesh() const { return mesh_; }
  const PartShape& shape() const { return shape_; }
  const std::vector<StressProfile>& profiles() const { return profiles_; }
  const std::vector<double>& activity() const { return activity_; }
  const std::vector<int>& fixed_dofs() const { return fixed_dofs_; }
  // Dofs with no stiffness left (every element around them removed); held at zero.
  const std::vector<char>& orphan_dofs() const { return orphan_; }
  // Nodes that still touch material.
  std::vector<char> live_nodes() const;
  // u0 (ndof x profiles).
  const Eigen::MatrixXd& equilibration_displacement() const { return u0_; }
  // max |f_R + K u0| / max |f_R| over the free dofs after equilibration: how well sigma0 balances.
  double equilibrium_residual() const { return relative_residual_; }

  // Element-average total stress sigma_R + C eps(u0 + u) for profile p.
  std::vector<Vector6d> element_stresses(int p, const Eigen::VectorXd& u) const;
  // sigma0 = sigma_R + C eps(u0) of profile p at reference point xi of element e: the equilibrated
  // stock's stress, which another FE code takes as its initial stress (fem/calculix_deck.hpp).
  Vector6d initial_stress(int p, int e, const Eigen::Vector3d& xi) const;

  const SolverStats& solver_stats() const { return solver_.stats(); }
  // The stiffness factorized by the last assemble_and_factorize() or anchor (lower triangle, held dofs).
  const Eigen::SparseMatrix<double>& stiffness() const { return K_; }
  double assembly_seconds() const { return assembly_seconds_; }
  Eigen::Index unknowns() const { return static_cast<Eigen::Index>(mesh_.dof_count()); }

 private:
  Eigen::SparseMatrix<double> assemble_stiffness(const std::vector<double>& fraction);
  // f_R,e + K_e u0_e per profile (3n x P), computed once per element and kept: every station loads
  // all the material removed so far, so without the cache a late station recomputes hundreds.
  const Eigen::MatrixXd& element_load(int e);
  Eigen::MatrixXd stress_load(int e) const;  // f_R,e per profile, group by group
  Eigen::MatrixXd solve_by_group(const Eigen::MatrixXd& rhs);
  // Calls f(first, count) for each group of profiles, in order.
  template <class F>
  void for_each_group(F&& f) const {
    for (Eigen::Index first = 0; Eigen::Index n : group_sizes_) f(first, n), first += n;
  }
  // Zeroes the held dofs' rows and columns and gives them the mean diagonal of the others (returned).
  double hold(Eigen::SparseMatrix<double>& K, const std::vector<char>& held) const;
  // The stiffness at the current activity, held (orphan_ updated); `scale`, if given, gets the held
  // dofs' diagonal.
  Eigen::SparseMatrix<double> held_stiffness(double* scale = nullptr);
  // (element, a - a_then) for every element whose fraction differs from `then`'s.
  std::vector<std::pair<int, double>> changes_since(const std::vector<double>& then) const;
  std::vector<char> held_dofs();  // orphans (from the activity) and fixed dofs; updates orphan_
  // ||K u_p - f_p|| / ||f_p|| per column, for the current K.
  Eigen::VectorXd column_residuals(const Eigen::MatrixXd& F, const Eigen::MatrixXd& U);
  // Rows of dofs held now (orphans and fixed dofs) set to zero.
  void zero_held_rows(Eigen::MatrixXd& M) const;
  // The same on the block's rows only (relative to the whole ||f_p||).
  Eigen::VectorXd block_row_residuals(const Eigen::MatrixXd& F, const Eigen::MatrixXd& U);
  // R -= sum over the elements changed since the anchor of (a - a_anchor) K_e u_e; a node's three
  // rows of R start at row_of(node).
  template <class RowOf>
  void subtract_changed_elements(const Eigen::MatrixXd& U, RowOf row_of, Eigen::MatrixXd& R);
  Eigen::VectorXd gather(int e, const Eigen::VectorXd& u) const;

  const Mesh& mesh_;
  PartShape shape_;
  std::vector<StressProfile> profiles_;
  std::vector<Eigen::Index> group_sizes_;  // consecutive groups of profiles_ (set_profile_groups)
  ElementOperators operators_;
  StiffnessPattern pattern_;
  SpdSolver solver_;
  // The block refactorization: the anchor's state and its factor.
  std::unique_ptr<TrailingBlockCholesky> block_;
  bool block_current_ = false;  // the last factorization is the block one
  std::vector<int> base_ordering_;  // fill-reducing order of the pattern, computed once
  std::vector<int> last_change_;    // per element, of the current run (RunChanges::last)
  std::vector<double> factor_activity_;  // the activity the current S (its factor) stands for
  std::vector<char> factor_held_, anchor_held_;  // per dof: held at factor_activity_, at the anchor
  std::vector<int> block_index_;    // per dof: its index in the block, or -1
  std::vector<double> anchor_activity_;
  Eigen::SparseMatrix<double, Eigen::RowMajor> block_rows_;  // the anchor's K on the block's rows (m x n)
  int block_solves_ = 0;                                     // since the anchor
  double anchor_scale_ = 1;
  double residual_bound_ = 1e-8;
  double full_flops_ = 0;  // of a full factorization in base_ordering_
  bool measure_full_residual_ = false;
  BlockStats block_stats_;

  std::vector<double> activity_;
  std::vector<int> fixed_dofs_;
  std::vector<char> orphan_;
  Eigen::SparseMatrix<double> K_;
  Eigen::MatrixXd u0_, r0_;
  std::vector<Eigen::MatrixXd> element_loads_;  // element_load's, empty until asked; reset with u0_
  double relative_residual_ = 0;
  double assembly_seconds_ = 0;
  bool equilibrated_ = false;
};

}  // namespace drom::fem
