#include "paths/copy/packets.hpp"

#include "geometry/cloud_kdtree.hpp"
#include "paths/copy/sphere_normals.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <tuple>

namespace drom::paths {

namespace {

using Column = std::vector<std::uint64_t>;

int popcount(const Column& c) {
  int n = 0;
  for (const auto w : c) n += std::popcount(w);
  return n;
}

struct Score {
  int cover = 0, overlap = 0;
};

// Points seen by one column at least, and by two at least (ones/twos counters over the columns).
Score score(const VisibilityMatrix& m, const std::vector<int>& chosen) {
  Score s;
  const std::size_t words = m.columns.empty() ? 0 : m.columns.front().size();
  for (std::size_t w = 0; w < words; ++w) {
    std::uint64_t ones = 0, twos = 0;
    for (const int j : chosen) {
      const std::uint64_t c = m.columns[static_cast<std::size_t>(j)][w];
      twos |= ones & c;
      ones |= c;
    }
    s.cover += std::popcount(ones), s.overlap += std::popcount(twos);
  }
  return s;
}

// Feasible (coverage reached) first, then the fewest overlap points, then the most covered.
bool better(const Score& a, const Score& b, int target) {
  const bool fa = a.cover >= target, fb = b.cover >= target;
  if (fa != fb) return fa;
  if (fa) return a.overlap < b.overlap || (a.overlap == b.overlap && a.cover > b.cover);
  return a.cover > b.cover || (a.cover == b.cover && a.overlap < b.overlap);
}

}  // namespace

std::vector<int> Packets::sizes() const {
  std::vector<int> n(directions.size(), 0);
  for (const int p : packet_of)
    if (p >= 0) ++n[static_cast<std::size_t>(p)];
  return n;
}

Packets group_packets(const VisibilityMatrix& m, std::span<const Eigen::Vector3d> points, std::span<const Eigen::Vector3d> normals, const PacketSettings& s,
                      const std::function<bool(int, int)>& reaches) {
  Packets out;
  const int n = m.points;
  out.packet_of.assign(static_cast<std::size_t>(n), -1);
  out.overlap.assign(static_cast<std::size_t>(n), 0);
  if (n == 0) return out;
  const int target = static_cast<int>(std::ceil(s.coverage * n - 1e-9));
  std::vector<int> candidates, count(m.columns.size(), 0);
  for (std::size_t j = 0; j < m.columns.size(); ++j) {
    count[j] = popcount(m.columns[j]);
    if (m.reachable[j] && count[j] >= std::max(1, s.min_points)) candidates.push_back(static_cast<int>(j));
  }
  if (candidates.empty()) {
    out.method = "no direction sees any point";
    out.unmachinable = n;
    return out;
  }

  // One direction.
  std::vector<int> chosen = {*std::max_element(candidates.begin(), candidates.end(), [&](int a, int b) { return count[static_cast<std::size_t>(a)] < count[static_cast<std::size_t>(b)]; })};
  Score best = score(m, chosen);
  out.combinations = static_cast<long long>(candidates.size());
  out.method = "one direction";
  // Every pair.
  if (best.cover < target && s.max_packets >= 2) {
    out.method = "every pair";
    std::vector<int> pair_best;
    Score pair_score{-1, 0};
    const std::size_t words = m.columns.front().size();
    for (std::size_t a = 0; a < candidates.size(); ++a)
      for (std::size_t b = a + 1; b < candidates.size(); ++b) {
        const int ja = candidates[a], jb = candidates[b];
        if (count[static_cast<std::size_t>(ja)] + count[static_cast<std::size_t>(jb)] < target) continue;
        ++out.combinations;
        const Column &ca = m.columns[static_cast<std::size_t>(ja)], &cb = m.columns[static_cast<std::size_t>(jb)];
        Score sc;
        for (std::size_t w = 0; w < words; ++w) sc.cover += std::popcount(ca[w] | cb[w]);
        sc.overlap = count[static_cast<std::size_t>(ja)] + count[static_cast<std::size_t>(jb)] - sc.cover;
        if (pair_best.empty() || better(sc, pair_score, target)) pair_best = {ja, jb}, pair_score = sc;
      }
    if (!pair_best.empty() && better(pair_score, best, target)) chosen = pair_best, best = pair_score;
  }
  // Three and more: greedy cover, then swaps while they help.
  for (int np = 3; best.cover < target && np <= s.max_packets; ++np) {
    out.method = "greedy cover and swaps";
    std::vector<int> trial;
    Score current;
    for (int k = 0; k < np; ++k) {
      int pick = -1;
      Score pick_score;
      for (const int j : candidates) {
        if (std::find(trial.begin(), trial.end(), j) != trial.end()) continue;
        trial.push_back(j);
        const Score sc = score(m, trial);
        trial.pop_back();
        ++out.combinations;
        if (pick < 0 || sc.cover > pick_score.cover || (sc.cover == pick_score.cover && sc.overlap < pick_score.overlap)) pick = j, pick_score = sc;
      }
      if (pick < 0) break;
      trial.push_back(pick);
      current = pick_score;
    }
    for (int round = 0; round < 100; ++round) {
      bool improved = false;
      for (std::size_t p = 0; p < trial.size(); ++p) {
        const int keep = trial[p];
        int swap_to = keep;
        Score swap_score = current;
        for (const int j : candidates) {
          if (std::find(trial.begin(), trial.end(), j) != trial.end()) continue;
          trial[p] = j;
          const Score sc = score(m, trial);
          ++out.combinations;
          if (better(sc, swap_score, target)) swap_to = j, swap_score = sc;
        }
        trial[p] = swap_to;
        if (swap_to != keep) improved = true, current = swap_score;
      }
      if (!improved) break;
    }
    if (better(current, best, target) || current.cover >= target) chosen = trial, best = current;
  }
  out.directions = chosen;
  out.covered = best.cover;
  out.coverage_met = best.cover >= target;

  // Every point to one packet.
  constexpr double kDegree = std::numbers::pi / 180;
  std::vector<int> leftovers;
  for (int i = 0; i < n; ++i) {
    int seen = 0, pick = -1;
    double pick_off = 1e300;
    for (std::size_t k = 0; k < chosen.size(); ++k) {
      if (!m.test(i, chosen[k])) continue;
      ++seen;
      const double off = std::abs(angle_between(m.directions.unit[static_cast<std::size_t>(chosen[k])], normals[static_cast<std::size_t>(i)]) - s.cone_middle * kDegree);
      if (off < pick_off) pick_off = off, pick = static_cast<int>(k);
    }
    out.packet_of[static_cast<std::size_t>(i)] = pick;
    out.overlap[static_cast<std::size_t>(i)] = seen >= 2;
    out.overlaps += seen >= 2;
    if (pick < 0) leftovers.push_back(i);
  }
  // Leftovers to the nearest packet that reaches them.
  std::vector<Eigen::Vector3d> grouped;
  std::vector<int> grouped_packet;
  for (int i = 0; i < n; ++i)
    if (out.packet_of[static_cast<std::size_t>(i)] >= 0) grouped.push_back(points[static_cast<std::size_t>(i)]), grouped_packet.push_back(out.packet_of[static_cast<std::size_t>(i)]);
  if (!grouped.empty() && !leftovers.empty()) {
    const geometry::CloudKdTree tree(grouped, 3);
    std::vector<int> near;
    std::vector<double> d2;
    std::vector<int> assignment(leftovers.size(), -1);
    for (std::size_t l = 0; l < leftovers.size(); ++l) {
      const int i = leftovers[l];
      tree.nearest(points[static_cast<std::size_t>(i)], std::min<int>(64, static_cast<int>(grouped.size())), near, d2);
      std::vector<int> order;  // packets by their nearest point
      for (const int g : near)
        if (std::find(order.begin(), order.end(), grouped_packet[static_cast<std::size_t>(g)]) == order.end()) order.push_back(grouped_packet[static_cast<std::size_t>(g)]);
      for (int k = 0; k < static_cast<int>(chosen.size()); ++k)
        if (std::find(order.begin(), order.end(), k) == order.end()) order.push_back(k);
      for (const int k : order)
        if (reaches(i, chosen[static_cast<std::size_t>(k)])) {
          assignment[l] = k;
          break;
        }
    }
    for (std::size_t l = 0; l < leftovers.size(); ++l) {
      out.packet_of[static_cast<std::size_t>(leftovers[l])] = assignment[l];
      (assignment[l] >= 0 ? out.reattached : out.unmachinable) += 1;
    }
  } else {
    out.unmachinable = static_cast<int>(leftovers.size());
  }
  return out;
}

}  // namespace drom::paths
