#pragma once
// The least a packet's finishing can cost (issue 45, item 6; the cloud's counterpart of
// paths/finish/length_bound.hpp): passes a step w apart cover w mm² of surface per mm of pass, and no
// step that keeps the scallop bound is wider than the one on level ground (a ball's eq. 2.3 with R; a
// torus's flat bottom and two corner traces), so the passes are at least A / w long, A the surface
// the packet finishes. Its time is that length at the feed, plus a turn at each end of a pass.
//
// The area from points: the points in cubes of `cell` mm; a plane of unit normal n crosses
// (|n_x| + |n_y| + |n_z|) / cell^2 cubes per mm^2, so an occupied cube holds cell^2 / (|n_x| + |n_y| +
// |n_z|) of surface (n the mean of its points' normals): the same for any packet direction. The
// passes: the extent across them (the drop frame's Y) over the level-ground step.
//
// drom copy reports it beside each packet's finishing (summary.json `finishing.floor`), and the
// packets' choice ranks direction sets that tie on everything else by the sum of their packets'
// floor times (paths/copy/packets.hpp).
#include <Eigen/Core>

#include <span>

namespace drom::paths {

struct FinishingFloor {
  double area = 0;     // mm², of the surface the packet finishes
  double length = 0;   // mm: area / level-ground step
  double passes = 0;   // across the packet's extent at that step
  double time = 0;     // s: length at the feed, and a turn per pass
};

// `points`, `normals`: part frame; `members`: the packet's points (indices); `frame`: its drop frame
// (frame * part = drop); `step`: the level-ground step (mm); `feed`: mm/s; `turn`: s per pass end.
FinishingFloor finishing_floor(std::span<const Eigen::Vector3d> points, std::span<const Eigen::Vector3d> normals, std::span<const int> members,
                               const Eigen::Matrix3d& frame, double step, double feed, double turn, double cell);

}  // namespace drom::paths
