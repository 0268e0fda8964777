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
  if (offsets_.size() > 0 && t < offsets_.time(offsets_.size() - 1)) throw std::invalid_argument("MachinedFloor: offsets must be commanded in time order");
  offsets_.set(t, offset);
}

double MachinedFloor::offset_at(double t) const { return offsets_.at(t); }

std::optional<double> MachinedFloor::surface(double x, double y, const reduce::SurfacePoint& point, const SurfaceHistory& w, double t) const {
  const double s0 = target_.nominal_altitude(point);
  covers_.covers({x, y, s0}, t, scratch_);
  if (scratch_.empty()) return std::nullopt;
  const double lowest = reduce::lowest_cut(scratch_, w.times(), offsets_, [&](double, const reduce::TimeInterval& at) { return w.at_instant(point, at); }, instants_).bottom;
  return s0 + lowest + w.at_instant(point, t);
}

}  // namespace drom::online
