#pragma once
// A mesh adaptive direct search (MADS, Audet & Dennis) for bound-constrained black boxes that may be
// discontinuous and may fail (infeasible points return +inf: the extreme barrier). The poll uses
// the 2n directions of an orthogonal basis and their opposites (NOMAD's ORTHO 2N, with a
// deterministic rotation per iteration), is opportunistic (stops at the first improvement), and can
// be ordered by a cheap surrogate so the black box sees the most promising point first (how the
// seed uses its static surrogates, Herraz §4.4). Each evaluation reports its cost, so the budget
// counts black-box equivalents.
#include <Eigen/Core>

#include <functional>
#include <vector>

namespace drom::paths {

struct MadsSettings {
  double initial_step = 0.25;  // poll step, as a fraction of each variable's range
  double minimum_step = 1e-3;  // stop when the poll step falls below this (fraction of the range)
  double budget = 1000;        // stop when the evaluations' costs add up to this
};

struct MadsPoint {
  Eigen::VectorXd x;
  double value = 0;
  double cost = 1;  // black-box equivalents this evaluation used
};

struct MadsResult {
  Eigen::VectorXd best;
  double value = 0;
  double spent = 0;                      // black-box equivalents
  std::vector<std::pair<double, double>> history;  // (cost so far, best value so far) after each evaluation
};

// `evaluate` returns the value and its cost; `surrogate` (may be empty) ranks poll points, cheaply.
MadsResult mads_minimize(const std::function<MadsPoint(const Eigen::VectorXd&)>& evaluate, const std::function<double(const Eigen::VectorXd&)>& surrogate,
                         const Eigen::VectorXd& start, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, const MadsSettings& settings);

}  // namespace drom::paths
