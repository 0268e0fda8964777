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
    // The cover's ends, and every offset change and station inside it.
    instants_.assign({entry, exit});
    for (auto it = std::upper_bound(offsets_.begin(), offsets_.end(), entry, [](double v, const auto& e) { return v < e.first; });
         it != offsets_.end() && it->first < exit; ++it)
      instants_.push_back(it->first);
    for (const double* s = std::upper_bound(stations.data(), stations.data() + stations.size(), entry); s != stations.data() + stations.size() && *s < exit; ++s)
      instants_.push_back(*s);
    std::sort(instants_.begin(), instants_.end());
    // On each piece the offset is constant and w linear: its ends bound it.
    for (std::size_t i = 0; i + 1 < instants_.size(); ++i) {
      const double o = offset_at(instants_[i]);
      lowest = std::min({lowest, o - w.at_instant(point, instants_[i]), o - w.at_instant(point, instants_[i + 1])});
    }
  }
  return s0 + lowest + w.at_instant(point, t);
}

}  // namespace drom::online
