#include "offline/machining_run.hpp"

#include "fem/mesh_geometry.hpp"
#include "support/hdf5_writer.hpp"
#include "support/input_error.hpp"

#include <stdexcept>

namespace drom::offline {

MachiningRun::MachiningRun(const case_file::Case& c, const PartModel& part)
    : path_(build_toolpath(c, part)),
      timeline_(std::make_unique<levelset::PathTimeline>(path_)),
      stations_(c.stations == "waypoints" ? levelset::stations_at_waypoints(path_, *timeline_)
                                          : levelset::stations_by_spacing(path_, *timeline_, c.station_spacing)),
      voxel_(voxel_size_for(c, part)),
      removal_(std::make_unique<levelset::MaterialRemoval>(build_workpiece(c, part, voxel_), build_tool(c), voxel_)),
      elements_(part.mesh),
      criterion_(c.removal_criterion == "centroid" ? geometry::RemovalCriterion::Centroid : geometry::RemovalCriterion::VolumeFraction) {
  if (stations_.empty()) throw InputError(c.origin + ": the toolpath has no cutting move, so there is no station");
}

double MachiningRun::advance(std::vector<double>& remaining) {
  if (next_ >= stations_.size()) throw std::logic_error("MachiningRun::advance past the last station");
  const double to = stations_[next_++].path_length;
  const double removed = removal_->sweep(levelset::cutting_polylines(path_, *timeline_, swept_to_, to, 0.01));
  swept_to_ = to;
  removal_->update_remaining(elements_, criterion_, remaining, true);
  return removed;
}

bool frame_at(std::size_t k, std::size_t ns, std::size_t frames) { return frames > 0 && ((k + 1) * frames / ns != k * frames / ns || k + 1 == ns); }

void write_stations(Hdf5Writer& h5, const std::vector<levelset::Station>& stations) {
  const std::size_t ns = stations.size();
  std::vector<double> time(ns), length(ns), position(3 * ns);
  for (std::size_t k = 0; k < ns; ++k) {
    time[k] = stations[k].time;
    length[k] = stations[k].path_length;
    for (int d = 0; d < 3; ++d) position[3 * k + static_cast<std::size_t>(d)] = stations[k].position[d];
  }
  h5.write("station_time", time, ns, 1);
  h5.write("station_path_length", length, ns, 1);
  h5.write("station_position", position, ns, 3);
}

}  // namespace drom::offline
