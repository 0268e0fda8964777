#pragma once
// The tool-length offset commanded over program time, a step function, indexed for the lowest-cut
// search. That search weighs, over the stretch of time the tool covered a point, every change of the
// offset: a 100 Hz control loop puts some 250 of them under a 25 mm tool at 10 mm/s, and a laser
// profile asks for them at hundreds of points. At a change the tool has cut at both values, so the
// change stands for the lower one ("low"); between stored instants the surface moves linearly in
// time, so a cut's bottom there is low - m (t - a) for a slope m the point's own. The lower convex
// hulls of the changes over aligned blocks of 2^l of them answer the least of that over any range of
// changes in O(log^2 n) instead of a scan.
#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace drom::reduce {

// A step function of time: changes (time, value from then on), times increasing; 0 before the first.
class OffsetHistory {
 public:
  static constexpr std::size_t npos = static_cast<std::size_t>(-1);

  // The value from t on; nothing if it is already the value at t. Appending is amortized O(log n); a
  // t before the last change re-indexes the changes after it.
  void set(double t, double value);
  double at(double t) const { return value_before(changes_up_to(t)); }
  std::size_t size() const { return time_.size(); }

  // Changes k with a < time(k) < b, as the index range [first, last).
  std::pair<std::size_t, std::size_t> inside(double a, double b) const;
  double time(std::size_t k) const { return time_[k]; }
  double value(std::size_t k) const { return value_[k]; }
  double value_before(std::size_t k) const { return k > 0 ? value_[k - 1] : 0.0; }  // in force just before change k
  double low(std::size_t k) const { return low_[k]; }  // the lower of the values either side of change k
  // low(k) - m (time(k) - a), the quantity both searches below compare.
  double sloped(std::size_t k, double m, double a) const { return low_[k] - m * (time_[k] - a); }
  // Over k in [first, last): the k of the least sloped(k, m, a) (npos if the range is empty); with
  // `below`, npos also when that least is not below it, which lets whole blocks be skipped on their
  // minimum without a hull search (a caller that already holds a lower candidate elsewhere) ...
  std::size_t least(std::size_t first, std::size_t last, double m, double a, double below = kNoBound) const;
  // ... and the earliest k with sloped(k, m, a) <= bound (npos if none).
  std::size_t earliest_at_most(std::size_t first, std::size_t last, double m, double a, double bound) const;
  static constexpr double kNoBound = 1e300;

 private:
  static constexpr int kBaseLevel = 3;  // blocks of fewer than 8 changes are scanned
  std::size_t changes_up_to(double t) const;  // how many changes are at or before t
  void reindex_from(std::size_t k);
  // The first k with !before(time(k)) (before true on a prefix of the times), searched from where t
  // falls if the changes were evenly spread.
  template <class Before>
  std::size_t partition_near(double t, Before before) const;
  void build_block(int level, std::size_t block);
  std::size_t block_least(int level, std::size_t block, double m) const;
  // A lower bound of sloped(k, m, a) over the block, from its least low and its time span: a block
  // above what the search needs is skipped without its hull search.
  double block_floor(int level, std::size_t block, double m, double a) const;
  std::size_t block_earliest(int level, std::size_t block, double m, double a, double bound) const;
  // Calls visit(level, block) for the aligned blocks tiling [first, last), in time order, with
  // level -1 for a single change.
  template <class Visit>
  void tile(std::size_t first, std::size_t last, Visit&& visit) const;

  std::vector<double> time_, value_, low_;
  // Per level l >= kBaseLevel (index l - kBaseLevel): the hull of block b is
  // hull_[l][start_[l][b] .. start_[l][b + 1]), change indices in time order.
  std::vector<std::vector<std::uint32_t>> hull_;  // 32-bit: a run's history is some 1e5-1e6 changes
  std::vector<std::vector<std::size_t>> start_;
  std::vector<std::vector<double>> block_low_;  // per level and block: the least low in it
};

}  // namespace drom::reduce
