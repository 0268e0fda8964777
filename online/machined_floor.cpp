#include "online/machined_floor.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace drom::online {

MachinedFloor::MachinedFloor(const reduce::LightModel& model)
    : target_(model.target),
      covers_(model.path, model.tool_radius, 0.02 * model.pocket_depth,
              model.target.node_count() > 0 ? model.target.nodes().row(2).maxCoeff() + 0.02 * model.pocket_depth : 0.0) {}

void MachinedFloor::command(double t, double offset) {
  if (!offsets_.empty() && t < offsets_.back().first) throw std::invalid_argument("MachinedFloor: offsets must be commanded in time order");
  if (offset_at(t) != offset) offsets_.emplace_back(t, offset);
}

double MachinedFloor::offset_at(double t) const {
  const auto it = std::upper_bound(offsets_.begin(), offsets_.end(), t, [](double v, const auto& e) { return v < e.first; });
  return it == offsets_.begin() ? 0.0 : std::prev(it)->second;
}

std::optional<double> MachinedFloor::surface(double x, double y, const reduce::SurfacePoint& point, const SurfaceHistory& w, double t) const {
  const double s0 = target_.nominal_altitude(point);
  covers_.covers({x, y, s0}, t, scratch_);
  if (scratch_.empty()) return std::nullopt;
  double lowest = std::numeric_limits<double>::infinity();
  const Eigen::VectorXd& stations = w.times();
  for (const auto& [entry, exit] : scratch_) {
    // w is linear between stations: the cover's pieces between them, each with w at its two ends.
    instants_.assign({entry});
    for (const double* s = std::upper_bound(stations.data(), stations.data() + stations.size(), entry); s != stations.data() + stations.size() && *s < exit; ++s)
      instants_.push_back(*s);
    instants_.push_back(exit);
    for (std::size_t i = 0; i + 1 < instants_.size(); ++i) {
      const double a = instants_[i], b = instants_[i + 1], wa = w.at_instant(point, a), wb = w.at_instant(point, b);
      auto w_at = [&](double tau) { return b > a ? wa + (wb - wa) * (tau - a) / (b - a) : wa; };
      // Each stretch of constant offset inside [a, b] is bounded by its ends.
      double from = a, o = offset_at(a);
      for (auto it = std::upper_bound(offsets_.begin(), offsets_.end(), a, [](double v, const auto& e) { return v < e.first; });
           it != offsets_.end() && it->first < b; ++it) {
        lowest = std::min({lowest, o - w_at(from), o - w_at(it->first)});
        from = it->first, o = it->second;
      }
      lowest = std::min({lowest, o - w_at(from), o - w_at(b)});
    }
  }
  return s0 + lowest + w.at_instant(point, t);
}

}  // namespace drom::online
