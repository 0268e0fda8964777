#pragma once
// The full-order problem of fem::ElasticProblem (docs/design.md §1, §3), solved by PGD on a TensorGrid:
//   1. equilibrate each stress profile on the intact free stock held 3-2-1 -> u0 (separated);
//   2. set the remaining material (per Hex27 element) and the held dofs;
//   3. solve  a_I(v, u) = - int I eps(v) : sigma_R - a_I(v, u0)  for each profile, warm-started from
//      that profile's previous solution.
// Same inputs and outputs as the 3D FE problem (dofs numbered on the matching Hex27 mesh), so the
// offline job can use either.
#include "fem/element_operators.hpp"
#include "fem/residual_stress.hpp"
#include "pgd/pgd_solver.hpp"

#include <vector>

namespace drom::pgd {

class PgdProblem {
 public:
  PgdProblem(const TensorGrid& grid, const fem::Material& material, std::vector<fem::StressProfile> profiles, PgdSettings settings,
             double penalty_factor, double indicator_tolerance);

  // Equilibrium of the intact free stock. The FE core holds it 3-2-1; here a weak elastic foundation
  // (SeparatedOperator::set_foundation) does, which differs by a rigid motion and a relative 1e-9 in
  // strain: sigma0 is the same, and rigid motions do no work in the machining load.
  void equilibrate();
  // The free part with the current material, for the unclamped final shape (rigid motion arbitrary:
  // remove it with the best fit, as for the FE core's 3-2-1 solution).
  const std::vector<SeparatedField>& solve_free();
  void adopt_equilibrium(const PgdProblem& other);
  // Remaining fraction per Hex27 element (removed below fem::ElasticProblem::kMinVolumeFraction).
  void set_activity(const std::vector<double>& activity);
  // Or an indicator built by the caller (e.g. the exact flat-bottom form).
  void set_indicator(const MaterialIndicator& indicator);
  void set_fixed_dofs(const std::vector<int>& dofs);
  // Displacement since the equilibrated, held stock, one separated field per profile. With
  // warm_start, each profile starts from its previous solve.
  const std::vector<SeparatedField>& solve(bool warm_start = true);

  const TensorGrid& grid() const { return grid_; }
  const std::vector<fem::StressProfile>& profiles() const { return profiles_; }
  const std::vector<SeparatedField>& solutions() const { return solutions_; }
  const std::vector<SeparatedField>& equilibration() const { return u0_; }
  const std::vector<PgdReport>& reports() const { return reports_; }
  const std::vector<PgdReport>& equilibration_reports() const { return u0_reports_; }
  const MaterialIndicator& indicator() const { return indicator_; }
  const std::vector<double>& activity() const { return activity_; }  // as represented by the indicator
  // Hex27 nodes touching remaining material.
  std::vector<char> live_nodes() const;
  const fem::SolverStats& plane_solver_stats() const { return solver_.plane_solver_stats(); }

 private:
  TensorGrid grid_;
  std::vector<fem::StressProfile> profiles_;
  SeparatedOperator op_;
  PgdSolver solver_;
  double penalty_factor_, indicator_tolerance_;
  std::vector<double> activity_;
  MaterialIndicator indicator_;
  std::vector<SeparatedField> u0_, solutions_;
  std::vector<PgdReport> u0_reports_, reports_;
  std::vector<PenaltyTerm> fixed_;
  static constexpr double kFoundation = 1e-9;
};

}  // namespace drom::pgd
