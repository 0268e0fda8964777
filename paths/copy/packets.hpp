#pragma once
// Grouping a cloud into packets, one per fixed orientation (Makki 2009 §3-4, Algorithm 4): the fewest
// directions whose columns of the visibility matrix cover at least pa of the points, and among those
// the combination with the fewest overlap points (seen by two directions or more: the witness lines'
// proxy). One direction is tried first, then every pair (exhaustively, with popcounts, skipping pairs
// whose two counts cannot reach pa), then for three and more a greedy cover improved by swaps (a local
// search), not the C(m, np) enumeration. Then:
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
  double coverage = 0.95;  // pa
  int max_packets = 6;     // np_max
  int min_points = 1;      // nv_min: a direction seeing fewer points is not a candidate
  double cone_middle = 45; // degrees: overlap points go to the direction nearest this angle from their normal
};

struct Packets {
  std::vector<int> directions;       // chosen directions (indices into the matrix's), one per packet
  std::vector<int> packet_of;        // per point: its packet, or -1 (unmachinable)
  std::vector<char> overlap;         // per point: seen by two chosen directions or more
  int covered = 0;                   // points the chosen directions see (before re-attachment)
  int overlaps = 0;
  int reattached = 0;                // leftovers given to a packet
  int unmachinable = 0;              // leftovers no packet reaches
  bool coverage_met = false;         // covered >= pa x points
  long long combinations = 0;        // examined (pairs, or greedy and swap moves)
  std::string method;                // "one direction", "every pair", "greedy cover and swaps"
  std::vector<int> sizes() const;    // points per packet, after re-attachment
};

// `points`, `normals`: the matrix's rows (part frame). `reaches(point, direction)`: whether a
// direction machines a leftover point with the whole window (the body test); used for re-attachment.
Packets group_packets(const VisibilityMatrix& matrix, std::span<const Eigen::Vector3d> points, std::span<const Eigen::Vector3d> normals, const PacketSettings& settings,
                      const std::function<bool(int point, int direction)>& reaches);

}  // namespace drom::paths
