// The offset history's hull searches and the lowest-cut search built on them, against brute force.
#include "reduce/cut_time.hpp"
#include "reduce/offset_history.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace drom::reduce;

namespace {

// A control loop's offset: a smooth ramp at 100 Hz with a few jumps and returns to earlier values
// (exact ties in `low`), and some settings out of time order.
OffsetHistory ramp(std::mt19937& rng, int count, bool out_of_order) {
  OffsetHistory h;
  std::uniform_real_distribution<double> u(0, 1);
  for (int i = 0; i < count; ++i) {
    const double t = 0.01 * i;
    double v = 0.02 * std::sin(t / 0.7) + 0.005 * std::sin(t / 0.11);
    if (u(rng) < 0.05) v = std::round(v * 200) / 200;  // back to a round value seen before
    h.set(t, v);
  }
  if (out_of_order)
    for (int i = 0; i < 20; ++i) h.set(0.01 * count * u(rng) + 0.003, 0.03 * (u(rng) - 0.5));
  return h;
}

}  // namespace

TEST(OffsetHistory, HullSearchesMatchAScan) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(0, 1);
  for (bool out_of_order : {false, true}) {
    const OffsetHistory h = ramp(rng, 3000, out_of_order);
    ASSERT_GT(h.size(), 2000u);
    for (int q = 0; q < 2000; ++q) {
      const double a = 32 * u(rng), b = a + 4 * u(rng);
      const auto [first, last] = h.inside(a, b);
      for (std::size_t k = first; k < last; ++k) ASSERT_TRUE(h.time(k) > a && h.time(k) < b);
      ASSERT_TRUE(first == 0 || h.time(first - 1) <= a);
      ASSERT_TRUE(last == h.size() || h.time(last) >= b);
      const double m = q % 5 == 0 ? 0.0 : 0.05 * (u(rng) - 0.5);
      std::size_t scan = OffsetHistory::npos;
      for (std::size_t k = first; k < last; ++k)
        if (scan == OffsetHistory::npos || h.sloped(k, m, a) < h.sloped(scan, m, a)) scan = k;
      const std::size_t least = h.least(first, last, m, a);
      if (scan == OffsetHistory::npos) {
        EXPECT_EQ(least, OffsetHistory::npos);
        continue;
      }
      ASSERT_NE(least, OffsetHistory::npos);
      EXPECT_NEAR(h.sloped(least, m, a), h.sloped(scan, m, a), 1e-15) << "query " << q;
      // With a bound the least must be below: the same change when it is (blocks skipped on their
      // floor must not change which of tied changes wins), none when it is not.
      for (const double shift : {-1e-3, -1e-12, 0.0, 1e-12, 1e-3 * u(rng)}) {
        const double below = h.sloped(scan, m, a) + shift;
        EXPECT_EQ(h.least(first, last, m, a, below), h.sloped(least, m, a) < below ? least : OffsetHistory::npos) << "query " << q << " shift " << shift;
      }
      // The earliest within a bound above the least.
      const double bound = h.sloped(scan, m, a) + (q % 3 == 0 ? 0.0 : 1e-3 * u(rng));
      std::size_t earliest = OffsetHistory::npos;
      for (std::size_t k = first; k < last && earliest == OffsetHistory::npos; ++k)
        if (h.sloped(k, m, a) <= bound) earliest = k;
      EXPECT_EQ(h.earliest_at_most(first, last, m, a, bound), earliest) << "query " << q;
    }
  }
}

TEST(OffsetHistory, InsideFindsTheChangesStrictlyBetweenTwoTimesHoweverTheyAreSpread) {
  // The search starts where a time would fall if the changes were evenly spread: check it on changes
  // bunched at the start (t = i^3) and at the end (t = i^(1/3)), so that the first guess falls short
  // and overshoots, with times before, after, between and exactly at changes.
  for (const double power : {3.0, 1.0 / 3.0}) {
    OffsetHistory h;
    std::vector<double> times;
    for (int i = 1; i <= 400; ++i) times.push_back(64 * std::pow(i / 400.0, power)), h.set(times.back(), i % 2 ? 0.01 * i : -0.01 * i);
    std::mt19937 rng(3);
    std::uniform_real_distribution<double> u(-0.1, 1.1);
    std::uniform_int_distribution<std::size_t> pick(0, times.size() - 1);
    for (int q = 0; q < 5000; ++q) {
      double a = q % 4 == 0 ? times[pick(rng)] : 64 * u(rng) * u(rng);
      double b = q % 3 == 0 ? times[pick(rng)] : 64 * u(rng);
      if (a > b) std::swap(a, b);
      const auto first = static_cast<std::size_t>(std::upper_bound(times.begin(), times.end(), a) - times.begin());
      const auto last = std::max(first, static_cast<std::size_t>(std::lower_bound(times.begin(), times.end(), b) - times.begin()));
      ASSERT_EQ(h.inside(a, b), std::make_pair(first, last)) << "power " << power << " a " << a << " b " << b;
    }
  }
}

TEST(OffsetHistory, LowIsTheLowerValueEitherSideOfAChange) {
  OffsetHistory h;
  h.set(1.0, 0.5);
  h.set(2.0, -0.25);
  h.set(3.0, 0.75);
  h.set(2.0, -0.25);  // no change: nothing stored
  ASSERT_EQ(h.size(), 3u);
  EXPECT_DOUBLE_EQ(h.low(0), 0.0);  // 0 before the first setting
  EXPECT_DOUBLE_EQ(h.low(1), -0.25);
  EXPECT_DOUBLE_EQ(h.low(2), -0.25);
  EXPECT_DOUBLE_EQ(h.at(0.5), 0.0);
  EXPECT_DOUBLE_EQ(h.at(2.5), -0.25);
  h.set(1.5, -1.0);  // out of time order: the changes after it are re-indexed
  ASSERT_EQ(h.size(), 4u);
  EXPECT_DOUBLE_EQ(h.low(2), -1.0);
  EXPECT_DOUBLE_EQ(h.at(1.7), -1.0);
}

// Every candidate the rule names (cover ends, instants, both values at every change), by brute force:
// the lowest bottom, and the earliest candidate within the margin of it.
TEST(LowestCut, FindsTheLowestCutAndTheEarliestWithinTheMargin) {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(0, 1);
  const OffsetHistory h = ramp(rng, 4000, false);
  const Eigen::VectorXd instants = Eigen::VectorXd::LinSpaced(17, 0, 40);
  auto w_exact = [](double tau) { return 0.01 * std::sin(tau / 3) + 0.002 * tau; };
  auto w_lin = [&](double tau) {
    const TimeInterval at = locate_time(instants, tau);
    return (1 - at.weight) * w_exact(instants[at.i]) + at.weight * w_exact(instants[at.i + 1]);
  };
  std::vector<CutPieceEnd> scratch;
  for (int q = 0; q < 500; ++q) {
    std::vector<std::pair<double, double>> covers;
    double t0 = 38 * u(rng);
    for (int c = 0; c < 1 + q % 3; ++c) {
      const double entry = t0, exit = std::min(39.9, entry + 2.5 * u(rng));
      covers.emplace_back(entry, exit);
      t0 = exit + 0.5;
      if (t0 > 39) break;
    }
    const double margin = q % 2 == 0 ? 0.0 : 2e-4;
    int calls_off_interval = 0;
    const LowestCut cut = lowest_cut(
        covers, instants, h,
        [&](double tau, TimeInterval at) {
          const TimeInterval expect = locate_time(instants, tau);
          if (expect.i != at.i || std::abs(expect.weight - at.weight) > 1e-12) ++calls_off_interval;
          return w_lin(tau);
        },
        scratch, margin);
    EXPECT_EQ(calls_off_interval, 0);
    struct Candidate {
      double tau, offset, bottom;
    };
    std::vector<Candidate> all;
    for (const auto& [entry, exit] : covers) {
      std::vector<double> taus{entry, exit};
      for (Eigen::Index i = 0; i < instants.size(); ++i)
        if (instants[i] > entry && instants[i] < exit) taus.push_back(instants[i]);
      for (double tau : taus) all.push_back({tau, h.at(tau), h.at(tau) - w_lin(tau)});
      for (std::size_t k = 0; k < h.size(); ++k)
        if (h.time(k) > entry && h.time(k) < exit)
          for (double o : {k > 0 ? h.value(k - 1) : 0.0, h.value(k)}) all.push_back({h.time(k), o, o - w_lin(h.time(k))});
    }
    double lowest = 1e300;
    for (const auto& c : all) lowest = std::min(lowest, c.bottom);
    double earliest = 1e300;
    for (const auto& c : all)
      if (c.bottom <= lowest + margin + 1e-14) earliest = std::min(earliest, c.tau);
    ASSERT_LE(cut.bottom, lowest + margin + 1e-14) << "query " << q;
    EXPECT_NEAR(cut.time, earliest, 1e-12) << "query " << q;
    EXPECT_NEAR(cut.offset - w_lin(cut.time), cut.bottom, 1e-12) << "query " << q;
    // The interval it reports is where its time lies (the covers stay inside the instants' span).
    EXPECT_NEAR((1 - cut.at.weight) * instants[cut.at.i] + cut.at.weight * instants[cut.at.i + 1], cut.time, 1e-12) << "query " << q;
    // Independently: no time of any cover, sampled finely, cuts lower.
    for (const auto& [entry, exit] : covers)
      for (double tau = entry; tau <= exit; tau += 1e-3) ASSERT_GE(h.at(tau) - w_lin(tau), cut.bottom - margin - 1e-12) << "query " << q << " tau " << tau;
  }
}
