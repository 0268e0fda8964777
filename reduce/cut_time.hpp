#pragma once
// When the tool first cut a point of the target surface: the first program time at which the tool,
// its tip down at the point's altitude (within a tolerance), covers the point (horizontal distance
// <= the tool radius). The light model stores it per target node; the predictor needs it at every
// laser point, where a face's nodes may have been cut passes apart, so segments are bucketed on a
// grid and a query looks at the few that pass nearby.
#include <Eigen/Core>

#include <algorithm>
#include <limits>
#include <utility>
#include <vector>

namespace drom::reduce {

// A step function of time: (time, value from then on), times increasing; 0 before the first.
using StepFunction = std::vector<std::pair<double, double>>;
inline double step_value(const StepFunction& steps, double t) {
  const auto it = std::upper_bound(steps.begin(), steps.end(), t, [](double v, const auto& e) { return v < e.first; });
  return it == steps.begin() ? 0.0 : std::prev(it)->second;
}

struct LowestCut {
  double bottom = std::numeric_limits<double>::infinity();  // offset - w at the winning instant
  double time = 0, offset = 0;
};

// Of the tool's covers of a point (entry, exit), the cut with the lowest bottom in the material's
// frame, offset(tau) - w(tau): the floor a flat tool leaves there. w is linear between `instants`
// (w_at(tau) evaluates it at any instant) and the offset a step function, so the minimum lies at a
// cover's ends, an offset change or an instant, and w between them is interpolated from its ends. A
// candidate wins only when lower by more than `margin` (the earlier one keeps near-ties).
template <class W>
LowestCut lowest_cut(const std::vector<std::pair<double, double>>& covers, const Eigen::VectorXd& instants, const StepFunction& offsets, W&& w_at,
                     std::vector<double>& pieces, double margin = 0) {
  LowestCut best;
  if (!covers.empty()) best.time = covers.front().first;
  auto consider = [&](double o, double w, double tau) {
    if (o - w < best.bottom - margin) best = {o - w, tau, o};
  };
  for (const auto& [entry, exit] : covers) {
    pieces.assign({entry});
    for (const double* c = std::upper_bound(instants.data(), instants.data() + instants.size(), entry); c != instants.data() + instants.size() && *c < exit; ++c)
      pieces.push_back(*c);
    pieces.push_back(exit);
    for (std::size_t i = 0; i + 1 < pieces.size(); ++i) {
      const double a = pieces[i], b = pieces[i + 1], wa = w_at(a), wb = w_at(b);
      auto w_lin = [&](double tau) { return b > a ? wa + (wb - wa) * (tau - a) / (b - a) : wa; };
      // Each stretch of constant offset inside [a, b] is bounded by its ends.
      double from = a, o = step_value(offsets, a);
      for (auto it = std::upper_bound(offsets.begin(), offsets.end(), a, [](double v, const auto& e) { return v < e.first; }); it != offsets.end() && it->first < b;
           ++it) {
        consider(o, w_lin(from), from);
        consider(o, w_lin(it->first), it->first);
        from = it->first, o = it->second;
      }
      consider(o, w_lin(from), from);
      consider(o, w_lin(b), b);
    }
  }
  return best;
}

// path: waypoints x, y, z, program time. `cutting` (optional, one flag per segment i -> i + 1): only
// those segments count; empty: every segment (moves above the floor are excluded by the altitude test).
double first_cover_time(const Eigen::MatrixXd& path, const std::vector<char>& cutting, const Eigen::Vector3d& point, double radius, double z_tolerance);

class CutTimeIndex {
 public:
  CutTimeIndex() = default;
  // Segments whose lowest end lies below `z_max` only (the rest never reach the floor).
  CutTimeIndex(const Eigen::MatrixXd& path, double radius, double z_tolerance, double z_max);
  // +inf where the tool never covers the point.
  double at(const Eigen::Vector3d& point) const;
  // Every stretch of program time during which the tool covers the point (entry, exit), in time
  // order, up to `until` (a stretch in progress then ends at `until`). The floor a flat tool leaves
  // is the lowest of its passes over the point, so the last cover is not always the one that counts.
  void covers(const Eigen::Vector3d& point, double until, std::vector<std::pair<double, double>>& out) const;

 private:
  Eigen::MatrixXd path_;
  double radius_ = 0, z_tolerance_ = 0;
  double x0_ = 0, y0_ = 0, cell_ = 1;
  int nx_ = 0, ny_ = 0;
  std::vector<std::vector<int>> buckets_;  // segment indices (sorted, so the first hit in time order wins ties)
};

}  // namespace drom::reduce
