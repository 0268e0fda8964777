#pragma once
// Z-level roughing against the voxel map of a cloud (Makki 2009 §2.2): layers Z_i = Z_top - i ap in a
// drop frame, a zigzag of nodes (pl along the passes, pt across) in each, a node cut when the tool
// standing there clears the voxels' barycentres by the stock allowance. Where the seed only sketches
// the test, here it is conservative: a barycentre stands for every point of its voxel (within the
// voxel's diagonal of it), and for the move to the next node (half a step either way), so the tool
// never comes nearer than the allowance to any point of the cloud.
//
// Entries. The seed ramps down at a fixed angle from the previous layer, never checked, so it cannot
// rough pockets (its Fig. 2.8). Here a segment is entered from the side where it starts outside the
// stock; else by a straight ramp along the segment (then back to its start), or by a zigzag ramp
// within it where it is shorter than the ramp; every ramp is checked against the cloud, and against
// the material the layer above left (it must descend through cleared space). A segment that admits no
// safe entry is left, and counted: never a plunge.
#include "geometry/cloud_voxel_map.hpp"
#include "geometry/point_cloud.hpp"
#include "paths/copy/cloud_area.hpp"
#include "paths/copy/cloud_path.hpp"
#include "paths/cutter/tool_assembly.hpp"

#include <Eigen/Core>


namespace drom::paths {

struct CloudRoughingSettings {
  ToolAssembly tool;               // a flat end mill (the seed's D10), or a bull-nose
  double longitudinal_step = 3;    // pl, mm (the hip's)
  double transverse_step = 3;      // pt, mm
  double depth = 2;                // ap, mm per layer
  double allowance = 0.5;          // mm of stock left over the cloud for finishing, at least
  double voxel = 0;                // voxel edge, mm; 0: min(pl, pt, ap) / 4
  double ramp_angle = 3;           // degrees below the horizontal
  double clearance = 2;            // mm over the stock's top for traverses
};

struct CloudRoughing {
  CloudPath path;                  // drop frame
  int layers = 0;
  long long nodes = 0;             // node x layer positions inside the stock
  long long cut = 0;               // of those, machined
  long long blocked = 0;           // too near the cloud
  long long unreachable = 0;       // free, but in a segment no entry reaches (left as stock)
  int segments = 0, side_entries = 0, ramps = 0, zigzag_ramps = 0, skipped_segments = 0, links = 0, retracts = 0;
  std::size_t voxels = 0;          // full voxels of the map
  double voxel = 0;                // its edge, mm
  double inflation = 0;            // mm added to the allowance: the voxel's diagonal and half a step
  double top = 0, bottom = 0;      // the first and last layers' Z (drop frame)
};

// The voxel edge for these settings (the map is built by the caller, once for all packets).
double roughing_voxel(const CloudRoughingSettings& settings);

// `map`: the cloud's voxel map (part frame); `q` the drop frame; `stock` the stock box (part frame);
// `area` where to rough (drop frame XY); `bottom` the lowest layer (drop frame Z). Throws
// std::invalid_argument on bad settings.
CloudRoughing plan_cloud_roughing(const geometry::CloudVoxelMap& map, const Eigen::Matrix3d& q, const geometry::Box3& stock, const CloudArea& area, double bottom,
                                  const CloudRoughingSettings& settings);

}  // namespace drom::paths
