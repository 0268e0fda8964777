#include "paths/copy/packets.hpp"

#include "geometry/cloud_kdtree.hpp"
#include "geometry/point_cloud.hpp"
#include "paths/copy/finishing_floor.hpp"
#include "paths/copy/sphere_normals.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <numbers>
#include <tuple>

namespace drom::paths {

namespace {

constexpr double kDegree = std::numbers::pi / 180;
constexpr double kTiltTie = 1e-6;  // degrees: tilts on the direction grid tie exactly
constexpr double kCycleTie = 0.02;  // estimated cycles within 2 % of each other tie

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

// Without an admissible set: the most covered, then the fewest overlap points.
bool more_covered(const Score& a, const Score& b) { return a.cover > b.cover || (a.cover == b.cover && a.overlap < b.overlap); }

// Greedy cover: np directions from `allowed`, each the one that adds the most coverage (then the fewest
// overlaps) to those already taken; `current` gets the set's score. Fewer when `allowed` runs out.
std::vector<int> greedy_cover(const VisibilityMatrix& m, const std::vector<int>& allowed, int np, Score& current, long long& combinations) {
  std::vector<int> trial;
  for (int k = 0; k < np; ++k) {
    int pick = -1;
    Score pick_score;
    for (const int j : allowed) {
      if (std::find(trial.begin(), trial.end(), j) != trial.end()) continue;
      trial.push_back(j);
      const Score sc = score(m, trial);
      trial.pop_back();
      ++combinations;
      if (pick < 0 || more_covered(sc, pick_score)) pick = j, pick_score = sc;
    }
    if (pick < 0) break;
    trial.push_back(pick);
    current = pick_score;
  }
  return trial;
}

struct Candidate {
  std::vector<int> set;  // sorted
  Score score;
  double largest = 0, sum = 0;  // tilts, degrees
  double cycle = 0;
};

// Criterion 3: -1 when a tilts less than b, 1 when more, 0 on a tie.
int compare_tilt(const Candidate& a, const Candidate& b) {
  if (a.largest < b.largest - kTiltTie) return -1;
  if (a.largest > b.largest + kTiltTie) return 1;
  if (a.sum < b.sum - kTiltTie) return -1;
  if (a.sum > b.sum + kTiltTie) return 1;
  return 0;
}

// The search for admissible sets of one size and the choice among them (criteria 1-5).
class Chooser {
 public:
  Chooser(const VisibilityMatrix& m, std::span<const Eigen::Vector3d> points, std::span<const Eigen::Vector3d> normals, const PacketSettings& s,
          std::vector<int> candidates, int target, Packets& out)
      : m_(m), points_(points), normals_(normals), s_(s), candidates_(std::move(candidates)), target_(target), out_(out) {
    count_.assign(m.columns.size(), 0);
    tilt_.assign(m.columns.size(), 0);
    for (std::size_t j = 0; j < m.columns.size(); ++j) count_[j] = popcount(m.columns[j]), tilt_[j] = tilt_from_z(m.directions.unit[j]);
    std::sort(candidates_.begin(), candidates_.end(), [&](int a, int b) { return std::tie(tilt_[static_cast<std::size_t>(a)], a) < std::tie(tilt_[static_cast<std::size_t>(b)], b); });
  }

  // Criteria 1-3 over the sets of `np` directions: the admissible ones of least tilt (all of them
  // for one and two directions; one set from the greedy cover and swaps beyond).
  bool search(int np) {
    ties_.clear();
    admissible_ = 0;
    if (np == 1) {
      for (const int j : candidates_)
        if (count_[static_cast<std::size_t>(j)] >= target_) consider({j}, score(m_, {j}));
      out_.combinations += static_cast<long long>(candidates_.size());
    } else if (np == 2) {
      const std::size_t words = m_.columns.front().size();
      for (std::size_t a = 0; a < candidates_.size(); ++a)
        for (std::size_t b = a + 1; b < candidates_.size(); ++b) {
          const int ja = candidates_[a], jb = candidates_[b];
          if (count_[static_cast<std::size_t>(ja)] + count_[static_cast<std::size_t>(jb)] < target_) continue;
          ++out_.combinations;
          const Column &ca = m_.columns[static_cast<std::size_t>(ja)], &cb = m_.columns[static_cast<std::size_t>(jb)];
          Score sc;
          for (std::size_t w = 0; w < words; ++w) sc.cover += std::popcount(ca[w] | cb[w]);
          if (sc.cover < target_) continue;
          sc.overlap = count_[static_cast<std::size_t>(ja)] + count_[static_cast<std::size_t>(jb)] - sc.cover;
          consider({std::min(ja, jb), std::max(ja, jb)}, sc);
        }
    } else {
      greedy_by_tilt(np);
    }
    return !ties_.empty();
  }

  // Criteria 4 and 5 among the sets left, and what decided.
  Candidate choose() {
    std::sort(ties_.begin(), ties_.end(), [](const Candidate& a, const Candidate& b) {
      return std::tie(a.score.overlap, b.score.cover, a.set) < std::tie(b.score.overlap, a.score.cover, b.set);
    });
    if (ties_.size() > static_cast<std::size_t>(s_.tied_sets)) ties_.resize(static_cast<std::size_t>(s_.tied_sets));
    out_.tied = static_cast<int>(ties_.size());
    for (Candidate& c : ties_) c.cycle = cycle(c.set);
    // The least cycle; cycles within 2 % of it (the floor is an estimate) tie, and the first of those
    // in overlap order is taken.
    std::size_t least = 0;
    for (std::size_t k = 1; k < ties_.size(); ++k)
      if (ties_[k].cycle < ties_[least].cycle) least = k;
    std::size_t best = ties_.size();
    bool cycle_tied = false;
    for (std::size_t k = 0; k < ties_.size(); ++k)
      if (ties_[k].cycle <= ties_[least].cycle * (1 + kCycleTie)) {
        if (best == ties_.size()) best = k;
        else cycle_tied = true;
      }
    if (admissible_ == 1) out_.decided_by = "coverage";
    else if (ties_.size() == 1) out_.decided_by = "least tilt";
    else out_.decided_by = cycle_tied ? "fewest overlaps" : "shortest cycle";
    return ties_[best];
  }

  double tilt(int j) const { return tilt_[static_cast<std::size_t>(j)]; }
  int count(int j) const { return count_[static_cast<std::size_t>(j)]; }

  // Criterion 4: the packets' finishing floors in time, each point in the packet that will finish it
  // (the direction seeing it nearest the window's middle, as the grouping assigns it).
  double cycle(const std::vector<int>& set) const {
    std::vector<std::vector<int>> members(set.size());
    for (int i = 0; i < m_.points; ++i) {
      int pick = -1;
      double pick_off = 1e300;
      for (std::size_t k = 0; k < set.size(); ++k) {
        if (!m_.test(i, set[k])) continue;
        const double off = std::abs(angle_between(m_.directions.unit[static_cast<std::size_t>(set[k])], normals_[static_cast<std::size_t>(i)]) - s_.cone_middle * kDegree);
        if (off < pick_off) pick_off = off, pick = static_cast<int>(k);
      }
      if (pick >= 0) members[static_cast<std::size_t>(pick)].push_back(i);
    }
    double total = 0;
    for (std::size_t k = 0; k < set.size(); ++k)
      total += finishing_floor(points_, normals_, members[k], geometry::frame_along(m_.directions.unit[static_cast<std::size_t>(set[k])]), s_.step, s_.feed, s_.turn,
                               s_.cell).time;
    return total;
  }

 private:
  void consider(std::vector<int> set, const Score& sc) {
    ++admissible_;
    Candidate c;
    c.set = std::move(set);
    c.score = sc;
    for (const int j : c.set) c.largest = std::max(c.largest, tilt(j)), c.sum += tilt(j);
    const int order = ties_.empty() ? -1 : compare_tilt(c, ties_.front());
    if (order < 0) ties_.clear();
    if (order <= 0) {
      ties_.push_back(std::move(c));
      // Keep the list bounded: the fewest overlaps go forward to the cycle.
      if (ties_.size() > 4 * static_cast<std::size_t>(s_.tied_sets) + 16) {
        std::sort(ties_.begin(), ties_.end(), [](const Candidate& a, const Candidate& b) { return std::tie(a.score.overlap, b.score.cover) < std::tie(b.score.overlap, a.score.cover); });
        ties_.resize(static_cast<std::size_t>(s_.tied_sets));
      }
    }
  }

  // Three directions and more: the tilt allowed grows from the least, and at each the greedy cover
  // with swaps (the most covered, then the fewest overlaps) is tried; the first admissible set is
  // then relieved of tilt by swaps that keep it admissible.
  void greedy_by_tilt(int np) {
    std::vector<double> levels;
    for (const int j : candidates_) levels.push_back(tilt(j));
    levels.erase(std::unique(levels.begin(), levels.end(), [](double a, double b) { return std::abs(a - b) <= kTiltTie; }), levels.end());
    for (const double cap : levels) {
      std::vector<int> allowed;
      for (const int j : candidates_)
        if (tilt(j) <= cap + kTiltTie) allowed.push_back(j);
      if (static_cast<int>(allowed.size()) < np) continue;
      Score current;
      std::vector<int> trial = greedy_cover(m_, allowed, np, current, out_.combinations);
      swap_while(trial, current, allowed, [](const Score& a, const Score& b, double, double) { return more_covered(a, b); });
      if (current.cover < target_) continue;
      // Relieve the tilt: a swap that keeps the set admissible and lowers the sum of tilts (or keeps it
      // and overlaps less).
      const int target = target_;
      swap_while(trial, current, allowed, [target](const Score& a, const Score& b, double sum_a, double sum_b) {
        if (a.cover < target) return false;
        if (sum_a < sum_b - kTiltTie) return true;
        return std::abs(sum_a - sum_b) <= kTiltTie && a.overlap < b.overlap;
      });
      std::sort(trial.begin(), trial.end());
      consider(trial, current);
      return;
    }
  }

  template <class Better>
  void swap_while(std::vector<int>& trial, Score& current, const std::vector<int>& allowed, Better better) {
    const auto sum_of = [&](const std::vector<int>& t) {
      double s = 0;
      for (const int j : t) s += tilt(j);
      return s;
    };
    for (int round = 0; round < 100; ++round) {
      bool improved = false;
      for (std::size_t p = 0; p < trial.size(); ++p) {
        const int keep = trial[p];
        int swap_to = keep;
        Score swap_score = current;
        double swap_sum = sum_of(trial);
        for (const int j : allowed) {
          if (std::find(trial.begin(), trial.end(), j) != trial.end()) continue;
          trial[p] = j;
          const Score sc = score(m_, trial);
          const double sum = sum_of(trial);
          ++out_.combinations;
          if (better(sc, swap_score, sum, swap_sum)) swap_to = j, swap_score = sc, swap_sum = sum;
        }
        trial[p] = swap_to;
        if (swap_to != keep) improved = true, current = swap_score;
      }
      if (!improved) break;
    }
  }

  const VisibilityMatrix& m_;
  std::span<const Eigen::Vector3d> points_, normals_;
  const PacketSettings& s_;
  std::vector<int> candidates_;
  const int target_;
  Packets& out_;
  std::vector<int> count_;
  std::vector<double> tilt_;
  std::vector<Candidate> ties_;
  long long admissible_ = 0;
};

// No set of at most np_max directions is admissible: the most covered one found (one direction,
// every pair, then greedy cover and swaps), the fewest overlaps among equals.
std::vector<int> most_covered(const VisibilityMatrix& m, const std::vector<int>& candidates, const Chooser& chooser, int max_packets, Packets& out, Score& best) {
  std::vector<int> chosen = {*std::max_element(candidates.begin(), candidates.end(), [&](int a, int b) { return chooser.count(a) < chooser.count(b); })};
  best = score(m, chosen);
  for (int np = 2; np <= max_packets; ++np) {
    Score current;
    const std::vector<int> trial = greedy_cover(m, candidates, np, current, out.combinations);
    if (more_covered(current, best)) chosen = trial, best = current;
  }
  return chosen;
}

}  // namespace

double tilt_from_z(const Eigen::Vector3d& d) { return std::atan2(std::hypot(d.x(), d.y()), d.z()) / kDegree; }

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
  std::vector<int> candidates;
  for (std::size_t j = 0; j < m.columns.size(); ++j)
    if (m.reachable[j] && popcount(m.columns[j]) >= std::max(1, s.min_points)) candidates.push_back(static_cast<int>(j));
  if (candidates.empty()) {
    out.method = "no direction sees any point";
    out.unmachinable = n;
    return out;
  }
  // The machinable points: those some candidate sees.
  Column all(m.columns.front().size(), 0);
  for (const int j : candidates)
    for (std::size_t w = 0; w < all.size(); ++w) all[w] |= m.columns[static_cast<std::size_t>(j)][w];
  out.machinable = popcount(all);
  const int target = static_cast<int>(std::ceil(s.coverage * out.machinable - 1e-9));

  Chooser chooser(m, points, normals, s, candidates, target, out);
  std::vector<int> chosen;
  Score best;
  for (int np = 1; np <= s.max_packets && chosen.empty(); ++np) {
    out.method = np == 1 ? "one direction" : np == 2 ? "every pair" : "greedy cover and swaps";
    if (!chooser.search(np)) continue;
    const Candidate c = chooser.choose();
    chosen = c.set, best = c.score;
    out.largest_tilt = c.largest, out.tilt_sum = c.sum, out.estimated_cycle = c.cycle;
  }
  if (chosen.empty()) {
    out.method = "most covered (none admissible)";
    out.decided_by = "most covered";
    chosen = most_covered(m, candidates, chooser, s.max_packets, out, best);
    for (const int j : chosen) out.largest_tilt = std::max(out.largest_tilt, chooser.tilt(j)), out.tilt_sum += chooser.tilt(j);
    out.estimated_cycle = chooser.cycle(chosen);
  }
  out.directions = chosen;
  out.covered = best.cover;
  out.coverage_met = best.cover >= target;

  // Every point to one packet.
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
