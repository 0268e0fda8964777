#pragma once
// A case's machining, ready to step through station by station: its tool, toolpath, timeline and
// stations, and the removal level set over the mesh's elements.
#include "offline/part_setup.hpp"
#include "fem/mesh_geometry.hpp"
#include "levelset/material_removal.hpp"
#include "levelset/toolpath.hpp"

#include <memory>
#include <vector>

namespace drom {
class Hdf5Writer;
}

namespace drom::offline {

// Whether station k of ns writes one of `frames` full-field frames: spread evenly, the last station
// always (none when frames is 0).
bool frame_at(std::size_t k, std::size_t ns, std::size_t frames);
// The stations' program times, path lengths and tool positions, as the datasets station_time,
// station_path_length and station_position (ns x 3).
void write_stations(Hdf5Writer& h5, const std::vector<levelset::Station>& stations);

class MachiningRun {
 public:
  // Throws InputError when the toolpath has no cutting move.
  MachiningRun(const case_file::Case& c, const PartModel& part);

  const levelset::Toolpath& path() const { return path_; }
  const levelset::PathTimeline& timeline() const { return *timeline_; }
  const std::vector<levelset::Station>& stations() const { return stations_; }
  double voxel_size() const { return voxel_; }
  const levelset::MaterialRemoval& removal() const { return *removal_; }

  // Sweeps the next station (in order) and updates the elements it touched in `remaining`
  // (one volume fraction per element, 1 = intact). Returns the volume this station removed.
  double advance(std::vector<double>& remaining);
  std::size_t next_station() const { return next_; }

 private:
  levelset::Toolpath path_;
  std::unique_ptr<levelset::PathTimeline> timeline_;  // refers to path_
  std::vector<levelset::Station> stations_;
  double voxel_ = 0;
  std::unique_ptr<levelset::MaterialRemoval> removal_;
  fem::MeshGeometry elements_;  // refers to the part's mesh, which outlives the run
  geometry::RemovalCriterion criterion_;
  std::size_t next_ = 0;
  double swept_to_ = 0;  // path length swept so far
};

}  // namespace drom::offline
