#pragma once
// Copying a scanned part by 3+2 machining of its cloud, with no surface rebuilt (Makki 2009, the
// whole chain of its Fig. 3.30): normals by sphere launching, the visibility matrix over the
// direction grid (tool window, body collisions with the cloud, the stock's base and the fixtures, the
// machine's reach), the packets, and per packet, in its own drop frame, roughing on the voxel map and
// finishing on the whole cloud; each path checked again against the cloud with the whole tool, made
// into CL data and 3+2 G-code through machine/'s post-processor, and timed on the machine.
#include "geometry/cloud_rim.hpp"
#include "geometry/point_cloud.hpp"
#include "machine/program_verdict.hpp"
#include "machine/cl_data.hpp"
#include "machine/kinematics.hpp"
#include "paths/copy/cloud_finishing.hpp"
#include "paths/copy/cloud_roughing.hpp"
#include "paths/copy/finishing_floor.hpp"
#include "paths/copy/copy_settings.hpp"
#include "paths/copy/packets.hpp"
#include "paths/copy/path_check.hpp"
#include "paths/copy/sphere_normals.hpp"
#include "paths/copy/visibility.hpp"

#include <functional>
#include <optional>
#include <string>
#include <vector>

namespace drom::paths {

// One operation (finishing or roughing) of one packet.
struct PacketOperation {
  CloudPath path;                  // drop frame
  machine::ClProgram cl;           // part frame
  std::string gcode;               // empty when it is not posted (see error)
  std::string error;               // why not: a block beyond a stroke, or moves deeper than the tolerance into the scan
  std::optional<machine::ProgramVerdict> verdict;  // the posted program read back (machine/program_verdict.hpp)
  double cycle_time = 0;           // s, predicted on the machine
  PathCheck check;                 // against the cloud and the obstacles, with the whole tool
};

struct PacketPlan {
  int direction = 0;               // in the visibility matrix
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();  // part frame
  Eigen::Vector2d rotary = Eigen::Vector2d::Zero();  // the machine's two rotary angles (degrees)
  Eigen::Matrix3d frame = Eigen::Matrix3d::Identity();  // drop frame: frame * part = drop
  int points = 0;                  // rows in the packet
  FinishingFloor floor;            // the least its finishing can cost (finishing_floor.hpp)
  std::optional<CloudFinishing> finishing;
  std::optional<CloudRoughing> roughing;
  PacketOperation finish_op, rough_op;
  std::string error;               // a packet whose area missed the cloud
};

struct StageTime {
  std::string stage;
  double wall = 0, cpu = 0;        // s (CPU: every thread of the process together)
};

struct CopyResult {
  std::size_t cloud_points = 0, obstacle_points = 0, side_points = 0;
  geometry::Box3 cloud_box, stock;
  double base_top = 0;                        // z of the stock base's top (the table the part stands on)
  double obstacle_spacing = 0;                // mm between the obstacles' and the side's points
  double hole_radius = 0;                     // mm: the widest gap the completion leaves in the scan
  geometry::CloudRim rim;                     // the scan's edge; the part's side stands below it
  double noise = 0;                           // the scan's noise (mm; geometry/cloud_noise.hpp)
  double spacing = 0, spacing_p90 = 0;        // the scan's typical spacing and its 90th percentile (mm)
  std::size_t crease_points = 0, crease_cells = 0, hole_points = 0;  // the completion's points (after the scan's, before the side)
  std::size_t noise_floor_points = 0;  // the completion's points above the noise (in pairs)
  double noise_floor_deviations = 0;   // their lift, in their fits' deviations
  std::vector<Eigen::Vector3d> completion, side;  // the points added to the scan, and the part's side (part frame)
  PointNormals normals;                       // the rows: points with a normal
  std::vector<Eigen::Vector3d> row_points, row_normals;
  bool normals_from_file = false;
  double pca_disagreement = 0;                // mean angle (deg) between the PCA and the launched normals
  VisibilityMatrix visibility;
  long long blocked_by_obstacles = 0;         // rows whose cutter, touching them, would enter an obstacle: seen by no direction
  Packets packets;
  std::vector<PacketPlan> plans;
  std::vector<StageTime> times;
};

// `cloud` in the part frame (scaled already); `machine` the kinematics of s.machine. Progress lines
// go to `progress` when given. Throws InputError when the cloud gives no normal or no direction
// sees any point.
CopyResult copy_cloud(const geometry::PointCloud& cloud, const CopySettings& settings, const machine::Kinematics& machine,
                      const std::function<void(const std::string&)>& progress = {});

}  // namespace drom::paths
