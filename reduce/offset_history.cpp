#include "reduce/offset_history.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace drom::reduce {

std::size_t OffsetHistory::changes_up_to(double t) const { return static_cast<std::size_t>(std::upper_bound(time_.begin(), time_.end(), t) - time_.begin()); }

void OffsetHistory::set(double t, double value) {
  // After any change at the same time, so that the latest setting wins.
  const std::size_t k = changes_up_to(t);
  if (value_before(k) == value) return;
  if (time_.size() >= std::numeric_limits<std::uint32_t>::max()) throw std::length_error("offset history: more than 2^32 changes");
  const auto at = static_cast<std::ptrdiff_t>(k);
  time_.insert(time_.begin() + at, t);
  value_.insert(value_.begin() + at, value);
  reindex_from(k);
}

void OffsetHistory::reindex_from(std::size_t k) {
  const std::size_t n = time_.size();
  low_.resize(n);
  for (std::size_t j = k; j < n; ++j) low_[j] = std::min(value_before(j), value_[j]);
  // Blocks that reach change k or later are stale; the rest stand.
  for (std::size_t level = 0; level < hull_.size(); ++level) {
    const std::size_t keep = k >> (level + kBaseLevel);
    if (start_[level].size() > keep + 1) {
      hull_[level].resize(start_[level][keep]);
      start_[level].resize(keep + 1);
      block_low_[level].resize(keep);
    }
  }
  // A block is built when its last change arrives, from its halves' hulls.
  for (std::size_t count = k + 1; count <= n; ++count)
    for (int l = kBaseLevel; count % (std::size_t{1} << l) == 0; ++l) build_block(l, (count >> l) - 1);
}

void OffsetHistory::build_block(int l, std::size_t block) {
  const auto level = static_cast<std::size_t>(l - kBaseLevel);
  if (hull_.size() <= level) hull_.emplace_back(), start_.emplace_back(1, 0), block_low_.emplace_back();
  auto& hull = hull_[level];
  const std::size_t begin = hull.size();
  auto add = [&](std::size_t k) {
    // Andrew's monotone chain, lower side: drop the last vertex while it does not turn left.
    while (hull.size() >= begin + 2) {
      const std::size_t o = hull[hull.size() - 2], a = hull.back();
      const double cross = (time_[a] - time_[o]) * (low_[k] - low_[o]) - (low_[a] - low_[o]) * (time_[k] - time_[o]);
      if (cross > 0) break;
      hull.pop_back();
    }
    hull.push_back(static_cast<std::uint32_t>(k));
  };
  if (level == 0) {
    for (std::size_t k = block << l; k < (block + 1) << l; ++k) add(k);
  } else {
    // The lower hull of a union lies on the halves' lower hulls.
    const auto& below = hull_[level - 1];
    const auto& at = start_[level - 1];
    for (std::size_t i = at[2 * block]; i < at[2 * block + 2]; ++i) add(below[i]);
  }
  start_[level].push_back(hull.size());
  // The least low is a vertex of the lower hull.
  double least_low = low_[hull[begin]];
  for (std::size_t i = begin + 1; i < hull.size(); ++i) least_low = std::min(least_low, low_[hull[i]]);
  block_low_[level].push_back(least_low);
}

double OffsetHistory::block_floor(int l, std::size_t block, double m, double a) const {
  const auto level = static_cast<std::size_t>(l - kBaseLevel);
  const double t0 = time_[block << l], t1 = time_[((block + 1) << l) - 1];
  return block_low_[level][block] - std::max(m * (t0 - a), m * (t1 - a));
}

template <class Before>
std::size_t OffsetHistory::partition_near(double t, Before before) const {
  // A control loop sets the offset at a fixed rate, so the changes are close to evenly spread in time:
  // the interpolated index lands within a few of the answer, and a galloping search from it costs
  // O(log distance) instead of a binary search's O(log n) over a whole run's history.
  const std::size_t n = time_.size();
  if (n == 0) return 0;
  const double span = time_.back() - time_.front();
  const double where = span > 0 && std::isfinite(t) ? std::clamp((t - time_.front()) / span, 0.0, 1.0) : 0.0;  // no cast of a NaN
  const auto guess = std::min(n - 1, static_cast<std::size_t>(where * static_cast<double>(n - 1)));
  std::size_t lo, hi;  // before(lo) (or lo = begin) and !before(hi) (or hi = n): the answer is in (lo, hi]
  auto at = [&](std::size_t k) { return time_.begin() + static_cast<std::ptrdiff_t>(k); };
  if (before(time_[guess])) {
    lo = guess;
    for (std::size_t step = 1;; step *= 2) {
      hi = lo + step;
      if (hi >= n) {
        hi = n;
        break;
      }
      if (!before(time_[hi])) break;
      lo = hi;
    }
    return static_cast<std::size_t>(std::partition_point(at(lo + 1), at(hi), before) - time_.begin());
  }
  hi = guess;
  for (std::size_t step = 1;; step *= 2) {
    if (hi < step) return static_cast<std::size_t>(std::partition_point(at(0), at(hi), before) - time_.begin());
    lo = hi - step;
    if (before(time_[lo])) break;
    hi = lo;
  }
  return static_cast<std::size_t>(std::partition_point(at(lo + 1), at(hi), before) - time_.begin());
}

std::pair<std::size_t, std::size_t> OffsetHistory::inside(double a, double b) const {
  const std::size_t first = partition_near(a, [a](double t) { return t <= a; });
  const std::size_t last = partition_near(b, [b](double t) { return t < b; });
  return {first, std::max(first, last)};
}

std::size_t OffsetHistory::block_least(int l, std::size_t block, double m) const {
  // low - m t is convex along a lower hull: the first vertex whose next edge rises at least as steeply as m.
  const auto level = static_cast<std::size_t>(l - kBaseLevel);
  const std::uint32_t* h = hull_[level].data() + start_[level][block];
  std::size_t lo = 0, hi = start_[level][block + 1] - start_[level][block] - 1;
  while (lo < hi) {
    const std::size_t mid = (lo + hi) / 2;
    if (low_[h[mid + 1]] - low_[h[mid]] >= m * (time_[h[mid + 1]] - time_[h[mid]])) hi = mid;
    else lo = mid + 1;
  }
  return h[lo];
}

template <class Visit>
void OffsetHistory::tile(std::size_t first, std::size_t last, Visit&& visit) const {
  std::size_t k = first;
  while (k < last) {
    int best = -1;
    for (int l = kBaseLevel;; ++l) {
      const std::size_t size = std::size_t{1} << l, level = static_cast<std::size_t>(l - kBaseLevel);
      if (k % size != 0 || k + size > last || level >= hull_.size() || (k >> l) + 1 >= start_[level].size()) break;
      best = l;
    }
    if (best < 0) {
      if (!visit(-1, k)) return;
      ++k;
    } else {
      if (!visit(best, k >> best)) return;
      k += std::size_t{1} << best;
    }
  }
}

namespace {
// The hulls' minima, the blocks' floors and the changes' own values are rounded differently: a block
// is searched when its minimum comes within this of the bound (the changes themselves are then
// compared exactly).
double with_slack(double bound) { return bound + 1e-12 * (1 + std::abs(bound)); }
}  // namespace

std::size_t OffsetHistory::least(std::size_t first, std::size_t last, double m, double a, double below) const {
  std::size_t best = npos;
  double best_value = 0;
  // A block whose floor is above both the best so far and `below` cannot hold the answer (ties with
  // the best go to the earlier change, which is the best already).
  const double skip_above = with_slack(below);
  tile(first, last, [&](int l, std::size_t where) {
    if (l >= 0) {
      const double floor = block_floor(l, where, m, a);
      if (floor > skip_above || (best != npos && floor > with_slack(best_value))) return true;
    }
    const std::size_t k = l < 0 ? where : block_least(l, where, m);
    const double v = sloped(k, m, a);
    if (best == npos || v < best_value) best = k, best_value = v;
    return true;
  });
  return best != npos && best_value < below ? best : npos;
}

std::size_t OffsetHistory::block_earliest(int l, std::size_t block, double m, double a, double bound) const {
  if (l == kBaseLevel) {
    for (std::size_t k = block << l; k < (block + 1) << l; ++k)
      if (sloped(k, m, a) <= bound) return k;
    return npos;
  }
  for (std::size_t half : {2 * block, 2 * block + 1}) {
    if (block_floor(l - 1, half, m, a) > with_slack(bound) || sloped(block_least(l - 1, half, m), m, a) > with_slack(bound)) continue;
    const std::size_t k = block_earliest(l - 1, half, m, a, bound);
    if (k != npos) return k;
  }
  return npos;
}

std::size_t OffsetHistory::earliest_at_most(std::size_t first, std::size_t last, double m, double a, double bound) const {
  std::size_t found = npos;
  tile(first, last, [&](int l, std::size_t where) {
    if (l < 0) {
      if (sloped(where, m, a) <= bound) found = where;
    } else if (block_floor(l, where, m, a) <= with_slack(bound) && sloped(block_least(l, where, m), m, a) <= with_slack(bound)) {
      found = block_earliest(l, where, m, a, bound);
    }
    return found == npos;
  });
  return found;
}

}  // namespace drom::reduce
