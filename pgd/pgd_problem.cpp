#include "pgd/pgd_problem.hpp"

#include <stdexcept>

namespace drom::pgd {

PgdProblem::PgdProblem(const TensorGrid& grid, const fem::Material& material, std::vector<fem::StressProfile> profiles, PgdSettings settings,
                       double penalty_factor, double indicator_tolerance)
    : grid_(grid),
      profiles_(std::move(profiles)),
      op_(grid, material),
      solver_(op_, settings),
      penalty_factor_(penalty_factor),
      indicator_tolerance_(indicator_tolerance),
      activity_(static_cast<std::size_t>(grid.plane_elements() * grid.nt), 1.0) {}

void PgdProblem::equilibrate() {
  op_.set_indicator(MaterialIndicator::intact());
  op_.set_penalty({}, penalty_factor_);
  op_.set_foundation(kFoundation);
  u0_.clear();
  u0_reports_.clear();
  for (const auto& profile : profiles_) {
    PgdReport report;
    u0_.push_back(solver_.solve(op_.stress_load(profile), nullptr, report));
    u0_reports_.push_back(report);
  }
  op_.set_foundation(0);
  op_.set_indicator(indicator_);
  op_.set_penalty(fixed_, penalty_factor_);
  solutions_.clear();
}

const std::vector<SeparatedField>& PgdProblem::solve_free() {
  op_.set_penalty({}, penalty_factor_);
  op_.set_foundation(kFoundation);
  solutions_.clear();
  const auto& u = solve(false);
  op_.set_foundation(0);
  op_.set_penalty(fixed_, penalty_factor_);
  return u;
}

void PgdProblem::adopt_equilibrium(const PgdProblem& other) {
  u0_ = other.u0_;
  u0_reports_ = other.u0_reports_;
}

void PgdProblem::set_activity(const std::vector<double>& activity) {
  if (activity.size() != activity_.size()) throw std::invalid_argument("PgdProblem: one remaining fraction per Hex27 element");
  activity_ = effective_activity(activity);
  indicator_ = MaterialIndicator::from_activity(grid_, activity_, indicator_tolerance_);
  op_.set_indicator(indicator_);
}

void PgdProblem::set_indicator(const MaterialIndicator& indicator) {
  indicator_ = indicator;
  for (int k = 0; k < grid_.nt; ++k)
    for (int e = 0; e < grid_.plane_elements(); ++e) activity_[static_cast<std::size_t>(grid_.element(e, k))] = indicator.value(e, k);
  op_.set_indicator(indicator_);
}

void PgdProblem::set_fixed_dofs(const std::vector<int>& dofs) {
  fixed_ = penalty_terms(grid_, dofs);
  op_.set_penalty(fixed_, penalty_factor_);
}

const std::vector<SeparatedField>& PgdProblem::solve(bool warm_start) {
  if (u0_.size() != profiles_.size()) throw std::logic_error("PgdProblem::solve before equilibrate");
  const bool have_previous = warm_start && solutions_.size() == profiles_.size();
  std::vector<SeparatedField> next;
  reports_.assign(profiles_.size(), {});
  for (std::size_t p = 0; p < profiles_.size(); ++p) {
    ComponentTensors F = op_.stress_load(profiles_[p]);
    op_.subtract_product(u0_[p], F, false);  // the elastic load of u0; supports do no work on it
    next.push_back(solver_.solve(F, have_previous ? &solutions_[p] : nullptr, reports_[p]));
  }
  solutions_ = std::move(next);
  return solutions_;
}

std::vector<char> PgdProblem::live_nodes() const {
  std::vector<char> live(static_cast<std::size_t>(grid_.node_count()), 0);
  for (int k = 0; k < grid_.nt; ++k)
    for (int e = 0; e < grid_.plane_elements(); ++e) {
      if (activity_[static_cast<std::size_t>(grid_.element(e, k))] <= 0) continue;
      for (int a : grid_.plane_element_nodes(e))
        for (int c = 0; c < 3; ++c) live[static_cast<std::size_t>(grid_.node(a, 2 * k + c))] = 1;
    }
  return live;
}

}  // namespace drom::pgd
