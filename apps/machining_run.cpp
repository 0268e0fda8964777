#include "apps/machining_run.hpp"

#include "fem/element_samples.hpp"
#include "support/input_error.hpp"

#include <stdexcept>

namespace drom::app {

MachiningRun::MachiningRun(const Case& c, const PartModel& part)
    : path_(build_toolpath(c, part)),
      timeline_(std::make_unique<levelset::PathTimeline>(path_)),
      stations_(c.stations == "waypoints" ? levelset::stations_at_waypoints(path_, *timeline_)
                                          : levelset::stations_by_spacing(path_, *timeline_, c.station_spacing)),
      voxel_(voxel_size_for(c, part)),
      removal_(std::make_unique<levelset::MaterialRemoval>(build_workpiece(c, part, voxel_), build_tool(c), voxel_)),
      samples_(fem::element_samples(part.mesh, 2 * 3 * voxel_)),  // sample cells as wide as the narrow band
      criterion_(c.removal_criterion == "centroid" ? levelset::RemovalCriterion::Centroid : levelset::RemovalCriterion::VolumeFraction) {
  if (stations_.empty()) throw InputError(c.origin + ": the toolpath has no cutting move, so there is no station");
}

double MachiningRun::advance(std::vector<double>& remaining) {
  if (next_ >= stations_.size()) throw std::logic_error("MachiningRun::advance past the last station");
  const double to = stations_[next_++].path_length;
  const double removed = removal_->sweep(levelset::cutting_polylines(path_, *timeline_, swept_to_, to, 0.01));
  swept_to_ = to;
  removal_->update_remaining(samples_, criterion_, remaining, true);
  return removed;
}

}  // namespace drom::app
