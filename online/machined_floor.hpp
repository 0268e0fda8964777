#pragma once
// The floor the tool has actually cut, evaluated exactly at any point. Where the tool passed over
// (x, y) at program time tau with offset o(tau) in force, it left the material point there at
// S0(x, y) + o(tau) (the programmed surface, shifted by the offset); that point then rides the part's
// displacement, so at time t it is at S0 + o(tau) + w(x, y, t) - w(x, y, tau). Covered more than
// once (passes overlap, and a flat tool covers a point for 2R / feed), the point keeps the lowest cut
// in the material's frame, min over tau of (o(tau) - w(x, y, tau)). Over one cover, o is a step
// function and w is linear between the truth's stations, so the minimum is at a cover's ends, an
// offset change or a station: the evaluation is exact, with no grid (a grid's cells misplace the cut
// instant by up to 1e-3 mm next to a moving tool).
//
// The tool's own envelope (scallops, a flat end mill's edge on a curved floor) is not modelled: it
// is there whether or not the part distorts, and the seed's measurement model ignores it too.
#include "online/surface_history.hpp"
#include "reduce/cut_time.hpp"
#include "reduce/light_model.hpp"

#include <Eigen/Core>

#include <optional>
#include <utility>
#include <vector>

namespace drom::online {

class MachinedFloor {
 public:
  // The program (path, tool) of the model; times are the tool's true program times.
  explicit MachinedFloor(const reduce::LightModel& model);

  // The offset in force from true program time t on (times increasing).
  void command(double t, double offset);
  double offset_at(double t) const;

  // Altitude at program time t of the floor at (x, y) (`point`: located on the target surface), w
  // being the part's displacement; nothing where the tool has not cut yet.
  std::optional<double> surface(double x, double y, const reduce::SurfacePoint& point, const SurfaceHistory& w, double t) const;

 private:
  const reduce::SurfaceMesh& target_;
  reduce::CutTimeIndex covers_;
  reduce::OffsetHistory offsets_;
  mutable std::vector<std::pair<double, double>> scratch_;
  mutable std::vector<reduce::CutPieceEnd> instants_;
};

}  // namespace drom::online
