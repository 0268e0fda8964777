#pragma once
// When the tool first cut a point of the target surface: the first program time at which the tool,
// its tip down at the point's altitude (within a tolerance), covers the point (horizontal distance
// <= the tool radius). The light model stores it per target node; the predictor needs it at every
// laser point, where a face's nodes may have been cut passes apart, so segments are bucketed on a
// grid and a query looks at the few that pass nearby.
#include "reduce/offset_history.hpp"
#include "reduce/space_time_field.hpp"
#include "reduce/surface_mesh.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <limits>
#include <tuple>
#include <utility>
#include <vector>

namespace drom::reduce {

struct LowestCut {
  double bottom = std::numeric_limits<double>::infinity();  // offset - w at the winning instant
  double time = 0, offset = 0;
  TimeInterval at;  // where `time` falls among the instants (as locate_time gives it)
};

// lowest_cut's scratch: the ends of the pieces the covers split into at the instants.
struct CutPieceEnd {
  double tau = 0, w = 0;
  Eigen::Index above = 0;       // the first instant after tau
  bool starts_cover = false;
  std::size_t first = 0, last = 0;  // the offset's changes inside the piece that starts here
  double slope = 0;                 // and w's slope over it
  double start_bottom = 0, end_bottom = 0;  // the piece's candidates at its ends
  double change_floor = 0;                  // no change inside the piece has a bottom below this
};

// Of the tool's covers of a point (entry, exit), the cut with the lowest bottom in the material's
// frame, offset(tau) - w(tau): the floor a flat tool leaves there. w is linear between `instants`
// and the offset a step function, so the minimum lies at a cover's ends, an offset change (at the
// lower of its two values) or an instant, and w between them is interpolated from its ends.
// w_at(tau, where) evaluates w at tau, `where` being locate_time(instants, tau), found here as the
// pieces are walked so that a caller holding w per instant needs no search. Of the candidates within
// `margin` of the lowest, the earliest wins (so near-ties do not flip with rounding).
template <class W>
LowestCut lowest_cut(const std::vector<std::pair<double, double>>& covers, const Eigen::VectorXd& instants, const OffsetHistory& offsets, W&& w_at,
                     std::vector<CutPieceEnd>& ends, double margin = 0) {
  const Eigen::Index n = instants.size();
  const double* t = instants.data();
  // tau's interval from `above`, the index of the first instant after it (locate_time's clamping).
  auto where = [&](double tau, Eigen::Index above) -> TimeInterval {
    if (n < 2 || above == 0) return {0, 0.0};
    if (above >= n) return {n - 2, 1.0};
    return {above - 1, (tau - t[above - 1]) / (t[above] - t[above - 1])};
  };
  if (covers.empty()) return {};
  ends.clear();
  for (const auto& [entry, exit] : covers) {
    const double* c = std::upper_bound(t, t + n, entry);
    ends.push_back({entry, 0, c - t, true});
    for (; c != t + n && *c < exit; ++c) ends.push_back({*c, 0, c - t + 1, false});
    ends.push_back({exit, 0, c - t, false});
  }
  for (auto& e : ends) e.w = w_at(e.tau, where(e.tau, e.above));
  // A piece's candidates: its start (the offset in force there), a change inside it (its lower
  // value), its end (the offset in force just before it).
  auto at_start = [&](std::size_t i) {
    const CutPieceEnd& a = ends[i];
    const double o = offsets.value_before(a.first);
    return LowestCut{o - a.w, a.tau, o, where(a.tau, a.above)};
  };
  auto at_change = [&](std::size_t i, std::size_t k) {
    const CutPieceEnd& a = ends[i];
    return LowestCut{offsets.sloped(k, a.slope, a.tau) - a.w, offsets.time(k), offsets.low(k), where(offsets.time(k), a.above)};
  };
  auto at_end = [&](std::size_t i) {
    const CutPieceEnd &a = ends[i], &b = ends[i + 1];
    const double o = offsets.value_before(a.last);
    return LowestCut{o - b.w, b.tau, o, where(b.tau, b.above)};
  };
  // The lowest: at a piece's ends, and at the offset's changes inside it (its hull search). Every
  // piece's ends first: the lowest of them bounds the searches, which then skip the blocks of changes
  // that cannot go below it (most of them, where the offset moves one way across a cover).
  // The ends' bottoms are kept: the two passes below compare them again.
  double lowest_end = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i + 1 < ends.size(); ++i) {
    if (ends[i + 1].starts_cover) continue;
    CutPieceEnd &a = ends[i], &b = ends[i + 1];
    std::tie(a.first, a.last) = offsets.inside(a.tau, b.tau);
    a.slope = b.tau > a.tau ? (b.w - a.w) / (b.tau - a.tau) : 0.0;
    a.start_bottom = offsets.value_before(a.first) - a.w;
    a.end_bottom = offsets.value_before(a.last) - b.w;
    lowest_end = std::min({lowest_end, a.start_bottom, a.end_bottom});
  }
  LowestCut lowest;
  std::size_t lowest_piece = 0;
  auto consider = [&](const LowestCut& c, std::size_t i) {
    if (c.bottom < lowest.bottom) lowest = c, lowest_piece = i;
  };
  for (std::size_t i = 0; i + 1 < ends.size(); ++i) {
    if (ends[i + 1].starts_cover) continue;
    CutPieceEnd& a = ends[i];
    if (a.start_bottom < lowest.bottom) lowest = at_start(i), lowest_piece = i;
    // A change is kept if it beats the lowest so far, so the search needs only those below the lowest
    // end (with room for sloped - w rounding apart from the bound + w it is compared with).
    const double below = std::min(lowest_end, lowest.bottom) + a.w;
    const double slack = 1e-9 * (1 + std::abs(below));
    if (const std::size_t k = offsets.least(a.first, a.last, a.slope, a.tau, below + slack); k != OffsetHistory::npos) {
      const LowestCut c = at_change(i, k);
      a.change_floor = c.bottom;
      consider(c, i);
    } else {
      a.change_floor = below + slack - a.w;  // none of its changes came below that
    }
    if (a.end_bottom < lowest.bottom) lowest = at_end(i), lowest_piece = i;
  }
  // The earliest candidate within the margin of it (at the latest, in the piece that holds it). A
  // piece whose changes all stayed clear above the bound (by more than the rounding of the bottoms)
  // is not searched again.
  const double bound = lowest.bottom + margin;
  const double rounding = 1e-12 * (1 + std::abs(bound));
  for (std::size_t i = 0; i <= lowest_piece; ++i) {
    if (ends[i + 1].starts_cover) continue;
    const CutPieceEnd& a = ends[i];
    if (a.start_bottom <= bound) return at_start(i);
    if (a.change_floor - rounding <= bound)
      if (const std::size_t k = offsets.earliest_at_most(a.first, a.last, a.slope, a.tau, bound + a.w); k != OffsetHistory::npos) return at_change(i, k);
    if (a.end_bottom <= bound) return at_end(i);
  }
  return lowest;  // rounding kept the lowest itself out of the search (sloped - w against bound + w)
}

// Whether the tool has reached none of the face's nodes by time t (`node_cut_time`: one per node of
// the face's surface, +inf where never cut).
inline bool face_uncut(const SurfacePoint& p, const Eigen::VectorXd& node_cut_time, double t) {
  for (int i = 0; i < p.count; ++i)
    if (!(node_cut_time[p.nodes[static_cast<std::size_t>(i)]] > t)) return false;
  return true;
}

// path: waypoints x, y, z, program time. `cutting` (optional, one flag per segment i -> i + 1): only
// those segments count; empty: every segment (moves above the floor are excluded by the altitude test).
double first_cover_time(const Eigen::MatrixXd& path, const std::vector<char>& cutting, const Eigen::Vector3d& point, double radius, double z_tolerance);

class CutTimeIndex {
 public:
  CutTimeIndex() = default;
  // Segments whose lowest end lies below `z_max` only (the rest never reach the floor).
  CutTimeIndex(const Eigen::MatrixXd& path, double radius, double z_tolerance, double z_max);
  // +inf where the tool never covers the point.
  double at(const Eigen::Vector3d& point) const;
  // Every stretch of program time during which the tool covers the point (entry, exit), in time
  // order, up to `until` (a stretch in progress then ends at `until`). The floor a flat tool leaves
  // is the lowest of its passes over the point, so the last cover is not always the one that counts.
  void covers(const Eigen::Vector3d& point, double until, std::vector<std::pair<double, double>>& out) const;

 private:
  Eigen::MatrixXd path_;
  // Each low segment as covers() reads it: contiguous, a line or two per candidate instead of the
  // path matrix's scattered columns.
  struct Segment {
    double ax = 0, ay = 0, dx = 0, dy = 0, A = 0;  // start, direction, |direction|^2
    double za = 0, zb = 0, t0 = 0, t1 = 0;         // tip altitudes and program times at its ends
  };
  std::vector<Segment> segments_;
  double radius_ = 0, z_tolerance_ = 0;
  bool bucket_of(const Eigen::Vector3d& point, int& i, int& j) const;
  double x0_ = 0, y0_ = 0, cell_ = 1;
  int nx_ = 0, ny_ = 0;
  std::vector<std::vector<int>> buckets_;  // segment indices (sorted, so the first hit in time order wins ties)
};

}  // namespace drom::reduce
