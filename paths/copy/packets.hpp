#pragma once
// Grouping a cloud into packets, one per fixed orientation (Makki 2009 §3-4, Algorithm 4), chosen as
// a CAM programmer would choose them (issue 45; docs/clouds.md §6.1 states the rule and a case where
// each criterion decides):
//   1. coverage: a set of directions is admissible when its columns of the visibility matrix cover at
//      least pa of the machinable points (those some direction the machine reaches sees at all);
//   2. the fewest packets among admissible sets (one direction, then every pair, then three and more
//      by greedy cover and swaps: the seed's C(m, np) enumeration is out of reach beyond pairs);
//   3. the least tilt from the machine's Z: the smallest largest tilt, then the smallest sum of tilts
//      (a part the vertical sees is a 3-axis job; the seed's hollow cone aside, nothing else makes it
//      one);
//   4. the shortest cycle: among sets still tied (the same tilts at other azimuths), the least sum of
//      their packets' finishing floors in time (paths/copy/finishing_floor.hpp), each point in the
//      packet that will finish it; an estimate, so cycles within 2 % of the least tie;
//   5. the seed's criterion last: the fewest overlap points (seen by two chosen directions or more,
//      the witness lines' proxy).
// Then:
//   - an overlap point goes to the packet whose direction is nearest the middle of the tool window
//     [v1, v2] from its normal (the seed leaves the rule unstated);
//   - a point no chosen direction sees is re-attached to the packet of its nearest grouped point
//     (the seed's "Hausdorff distance"), if that packet's direction reaches it with the whole window
//     [0, 90] and the tool's body clear; else to the next nearest packet that does; else it is left
//     unmachinable, and listed.
#include "paths/copy/visibility.hpp"

#include <Eigen/Core>

#include <functional>
#include <span>
#include <string>
#include <vector>

namespace drom::paths {

struct PacketSettings {
  double coverage = 0.99;  // pa, of the machinable points (issue 45's check; the seed used 95 %); leftovers are re-attached after
  int max_packets = 6;     // np_max
  int min_points = 1;      // nv_min: a direction seeing fewer points is not a candidate
  double cone_middle = 42.5;  // degrees: overlap points go to the direction nearest this angle from their normal
  // The cycle criterion (finishing_floor.hpp): the finishing's level-ground step (mm), feed (mm/s),
  // the time of a turn at a pass's end (s), and the area grid's cell (mm).
  double step = 0.35, feed = 2000.0 / 60, turn = 0.15, cell = 1;
  int tied_sets = 64;      // at most this many sets tied on criteria 1-3 are weighed by their cycle
};

struct Packets {
  std::vector<int> directions;       // chosen directions (indices into the matrix's), one per packet
  std::vector<int> packet_of;        // per point: its packet, or -1 (unmachinable)
  std::vector<char> overlap;         // per point: seen by two chosen directions or more
  int machinable = 0;                // points some reachable direction sees
  int covered = 0;                   // points the chosen directions see (before re-attachment)
  int overlaps = 0;
  int reattached = 0;                // leftovers given to a packet
  int unmachinable = 0;              // leftovers no packet reaches
  bool coverage_met = false;         // covered >= pa x machinable
  long long combinations = 0;        // examined (pairs, or greedy and swap moves)
  std::string method;                // "one direction", "every pair", "greedy cover and swaps"
  // Which criterion singled the set out among the admissible sets of its size: "coverage" (the only
  // one), "least tilt", "shortest cycle", "fewest overlaps"; "most covered" when none is admissible.
  std::string decided_by;
  int tied = 0;                      // admissible sets of that size tied on criteria 1-3
  double largest_tilt = 0, tilt_sum = 0;  // degrees from +Z
  double estimated_cycle = 0;        // s: the sum of the packets' finishing floors (criterion 4)
  std::vector<int> sizes() const;    // points per packet, after re-attachment
};

// `points`, `normals`: the matrix's rows (part frame). `reaches(point, direction)`: whether a
// direction machines a leftover point with the whole window (the body test); used for re-attachment.
Packets group_packets(const VisibilityMatrix& matrix, std::span<const Eigen::Vector3d> points, std::span<const Eigen::Vector3d> normals, const PacketSettings& settings,
                      const std::function<bool(int point, int direction)>& reaches);

// The tilt of a direction from the part frame's +Z (degrees).
double tilt_from_z(const Eigen::Vector3d& direction);

}  // namespace drom::paths
