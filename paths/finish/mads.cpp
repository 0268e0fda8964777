#include "paths/finish/mads.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace drom::paths {

namespace {

// The k-th point of the Halton sequence in dimension n (primes as bases), in (0, 1)^n.
Eigen::VectorXd halton(long k, int n) {
  static constexpr int primes[] = {2, 3, 5, 7, 11, 13, 17, 19, 23, 29, 31, 37, 41, 43, 47, 53, 59, 61, 67, 71, 73, 79, 83, 89, 97, 101, 103, 107, 109, 113};
  Eigen::VectorXd h(n);
  for (int d = 0; d < n; ++d) {
    const int b = primes[d % 30];
    double f = 1, r = 0;
    for (long i = k; i > 0; i /= b) {
      f /= b;
      r += f * static_cast<double>(i % b);
    }
    h(d) = r;
  }
  return h;
}

}  // namespace

MadsResult mads_minimize(const std::function<MadsPoint(const Eigen::VectorXd&)>& evaluate, const std::function<double(const Eigen::VectorXd&)>& surrogate,
                         const Eigen::VectorXd& start, const Eigen::VectorXd& lower, const Eigen::VectorXd& upper, const MadsSettings& s) {
  const int n = static_cast<int>(start.size());
  const Eigen::VectorXd range = upper - lower;
  MadsResult r;
  r.best = start.cwiseMax(lower).cwiseMin(upper);
  const auto run = [&](const Eigen::VectorXd& x) {
    const MadsPoint p = evaluate(x);
    r.spent += p.cost;
    return p.value;
  };
  r.value = run(r.best);
  r.history.emplace_back(r.spent, r.value);
  double step = s.initial_step;
  for (long iteration = 1; r.spent < s.budget && step >= s.minimum_step; ++iteration) {
    // ORTHO 2N: the columns of a Householder matrix H = I - 2 v v' / v'v and their opposites.
    const Eigen::VectorXd v = 2 * halton(iteration, n) - Eigen::VectorXd::Ones(n);
    Eigen::MatrixXd H = Eigen::MatrixXd::Identity(n, n);
    if (v.squaredNorm() > 1e-12) H -= 2 * v * v.transpose() / v.squaredNorm();
    std::vector<Eigen::VectorXd> poll;
    for (int j = 0; j < n; ++j)
      for (const double sign : {1.0, -1.0}) {
        const Eigen::VectorXd d = sign * H.col(j) / H.col(j).cwiseAbs().maxCoeff();
        const Eigen::VectorXd y = (r.best + step * d.cwiseProduct(range)).cwiseMax(lower).cwiseMin(upper);
        if ((y - r.best).cwiseAbs().maxCoeff() > 1e-12) poll.push_back(y);
      }
    if (surrogate) {
      std::vector<double> rank(poll.size());
      for (std::size_t k = 0; k < poll.size(); ++k) rank[k] = surrogate(poll[k]);
      std::vector<std::size_t> order(poll.size());
      std::iota(order.begin(), order.end(), 0);
      std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return rank[a] < rank[b]; });
      std::vector<Eigen::VectorXd> sorted;
      for (const std::size_t k : order) sorted.push_back(poll[k]);
      poll = std::move(sorted);
    }
    bool improved = false;
    for (const auto& y : poll) {
      if (r.spent >= s.budget) break;
      const double f = run(y);
      if (f < r.value) {
        r.value = f;
        r.best = y;
        improved = true;
      }
      r.history.emplace_back(r.spent, r.value);
      if (improved) break;  // opportunistic
    }
    step = improved ? std::min(2 * step, 0.5) : step / 2;
  }
  return r;
}

}  // namespace drom::paths
