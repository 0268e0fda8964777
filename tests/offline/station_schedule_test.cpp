// The pieces of issue 26's scheduling: station ranges, the balanced blocks dealt to the ranks, and
// the removal history rank 0 hands the others.
#include "offline/activity_history.hpp"
#include "offline/station_schedule.hpp"
#include "fem/structured_mesh.hpp"
#include "support/input_error.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <stdexcept>

using namespace drom::offline;

TEST(StationSchedule, RangesReadAsPythonSlicesAndBadOnesAreNamed) {
  EXPECT_EQ(parse_station_range("3:7", 10, "--stations"), (StationRange{3, 7}));
  EXPECT_EQ(parse_station_range("4:", 10, "--stations"), (StationRange{4, 10}));
  EXPECT_EQ(parse_station_range(":2", 10, "--stations"), (StationRange{0, 2}));
  for (const char* bad : {"7:3", "3:11", "x:4", "4", "3:3", "-1:4"}) {
    try {
      parse_station_range(bad, 10, "--stations");
      ADD_FAILURE() << bad;
    } catch (const drom::InputError& e) {
      EXPECT_NE(std::string(e.what()).find(std::string("--stations ") + bad), std::string::npos) << e.what();
    }
  }
}

TEST(StationSchedule, BlocksAreContiguousAndTheLargestIsAsSmallAsItCanBe) {
  // Late stations cost less (less material): costs falling from 1 to 0.1 over 40 stations.
  std::vector<double> costs(40);
  for (std::size_t k = 0; k < costs.size(); ++k) costs[k] = 1.0 - 0.9 * static_cast<double>(k) / 39.0;
  const auto tasks = chunk_tasks(costs.size(), 1, [](std::size_t) { return true; }, costs);
  ASSERT_EQ(tasks.size(), 40u);
  for (int ranks : {1, 2, 3, 7}) {
    const auto blocks = deal_blocks(tasks, ranks, 0);
    ASSERT_EQ(blocks.size(), static_cast<std::size_t>(ranks));
    std::size_t next = 0;
    double largest = 0;
    for (const auto& block : blocks) {
      double load = 0;
      for (const auto& t : block) {
        EXPECT_EQ(t.first, next);
        next = t.last;
        load += t.cost;
      }
      largest = std::max(largest, load);
    }
    EXPECT_EQ(next, 40u);
    // Optimal for contiguous blocks: brute force over every split (ranks <= 3), otherwise the bound.
    const double total = std::accumulate(costs.begin(), costs.end(), 0.0);
    double best = total;
    if (ranks == 2)
      for (std::size_t a = 0; a <= 40; ++a) best = std::min(best, std::max(std::accumulate(costs.begin(), costs.begin() + static_cast<long>(a), 0.0),
                                                                        std::accumulate(costs.begin() + static_cast<long>(a), costs.end(), 0.0)));
    if (ranks == 3)
      for (std::size_t a = 0; a <= 40; ++a)
        for (std::size_t b = a; b <= 40; ++b)
          best = std::min(best, std::max({std::accumulate(costs.begin(), costs.begin() + static_cast<long>(a), 0.0),
                                          std::accumulate(costs.begin() + static_cast<long>(a), costs.begin() + static_cast<long>(b), 0.0),
                                          std::accumulate(costs.begin() + static_cast<long>(b), costs.end(), 0.0)}));
    if (ranks <= 3) {
      EXPECT_NEAR(largest, best, 1e-9) << ranks << " ranks";
    } else {
      EXPECT_LT(largest, total / 7 + 1.0);  // within one station of the even share
    }
  }
  // With falling costs, the first rank gets fewer stations than the last.
  const auto two = deal_blocks(tasks, 2, 0);
  EXPECT_LT(two[0].size(), two[1].size());
}

TEST(StationSchedule, MeasuredTimesCalibrateTheLawBetweenAndBeyondThem) {
  const std::vector<double> law = {1.0, 0.8, 0.6, 0.5, 0.4, 0.2};
  // Nothing measured: the law.
  EXPECT_EQ(calibrated_costs(law, std::vector<double>(6, 0.0)), law);
  // Stations 1 and 4 measured at 2 and 6 s (ratios 2.5 and 15): station 0 takes 1's ratio, 5 takes
  // 4's, 2 and 3 the ratios a third and two thirds of the way; measured stations cost their time.
  const auto costs = calibrated_costs(law, {0, 2.0, 0, 0, 6.0, 0});
  EXPECT_DOUBLE_EQ(costs[0], 1.0 * 2.5);
  EXPECT_DOUBLE_EQ(costs[1], 2.0);
  EXPECT_DOUBLE_EQ(costs[2], 0.6 * (2.5 + (15 - 2.5) / 3));
  EXPECT_DOUBLE_EQ(costs[3], 0.5 * (2.5 + 2 * (15 - 2.5) / 3));
  EXPECT_DOUBLE_EQ(costs[4], 6.0);
  EXPECT_DOUBLE_EQ(costs[5], 0.2 * 15);
  EXPECT_THROW(calibrated_costs(law, {1.0}), std::invalid_argument);
}

TEST(StationSchedule, MeasuredCostsOverruleTheLawInTheDeal) {
  // The law says late stations are cheaper. A resumed run holds stations 0..9, measured as the law
  // says (1 s for the first), and 30..39, measured 6 times slower than the law (their clamps made the
  // solves harder, say); 10..29 are missing. Calibrated, their costs rise along the job, so two ranks
  // split them with more stations on the first rank, where the law alone would put fewer.
  std::vector<double> law(40), measured(40, 0.0);
  for (std::size_t k = 0; k < 40; ++k) law[k] = 1.0 - 0.9 * static_cast<double>(k) / 39.0;
  for (std::size_t k = 0; k < 10; ++k) measured[k] = law[k];
  for (std::size_t k = 30; k < 40; ++k) measured[k] = 6 * law[k];
  auto missing = [](std::size_t k) { return k >= 10 && k < 30; };
  const auto costs = calibrated_costs(law, measured);
  const auto blocks = deal_blocks(chunk_tasks(40, 1, missing, costs), 2, 0);
  const auto by_law = deal_blocks(chunk_tasks(40, 1, missing, law), 2, 0);
  // Brute force over the split of the 20 missing stations, with the calibrated costs.
  double best = 1e300;
  std::size_t best_split = 0;
  for (std::size_t a = 10; a <= 30; ++a) {
    const double largest = std::max(std::accumulate(costs.begin() + 10, costs.begin() + static_cast<long>(a), 0.0),
                                    std::accumulate(costs.begin() + static_cast<long>(a), costs.begin() + 30, 0.0));
    if (largest < best) best = largest, best_split = a;
  }
  EXPECT_EQ(blocks[0].size(), best_split - 10);
  EXPECT_GT(blocks[0].size(), blocks[1].size());
  EXPECT_LT(by_law[0].size(), by_law[1].size());
}

TEST(StationSchedule, ChunksRestartColdAtTheirFirstStationAndEndAtTheirLastMissingOne) {
  const std::vector<double> costs(40, 1.0);
  // Stations 0..20 saved: chunk 16..31 is solved from 16 (cold), to its last missing station.
  const auto tasks = chunk_tasks(40, 16, [](std::size_t k) { return k > 20 && k != 39; }, costs);
  ASSERT_EQ(tasks.size(), 2u);
  EXPECT_EQ(tasks[0].first, 16u);
  EXPECT_EQ(tasks[0].last, 32u);
  EXPECT_EQ(tasks[1].first, 32u);
  EXPECT_EQ(tasks[1].last, 39u);
}

TEST(ActivityHistory, ReplaysEveryStationBitForBitFromItsBytes) {
  ActivityHistory history(5);
  const std::vector<std::vector<double>> stations = {{1, 1, 0.5, 1, 1}, {1, 0.25, 0.5, 1, 1}, {1, 0.25, 0.5, 1, 1}, {0, 0, 1e-17, 1, 0.1}};
  for (const auto& s : stations) history.append(s);
  EXPECT_EQ(history.changes(), 6u);
  const auto copy = ActivityHistory::from_bytes(history.bytes(), "test");
  std::vector<double> running;
  for (std::size_t k = 0; k < stations.size(); ++k) {
    EXPECT_EQ(copy.at(k), stations[k]);
    copy.advance(k, running);
    EXPECT_EQ(running, stations[k]);
  }
  std::string broken = history.bytes();
  broken.resize(broken.size() - 3);
  EXPECT_THROW(ActivityHistory::from_bytes(broken, "test"), drom::InputError);
}

TEST(ActivityHistory, RunChangesSayWhichStationsChangeEachElementFirstAndLast) {
  ActivityHistory history(4);
  // Element 0 goes at stations 1 and 3; element 1 at station 2; element 2 only drifts below the
  // floor (from 5e-4 to 1e-4: removed both times for the FE); element 3 never changes.
  for (const auto& s : std::vector<std::vector<double>>{{1, 1, 5e-4, 1}, {0.6, 1, 5e-4, 1}, {0.6, 0.2, 1e-4, 1}, {0, 0.2, 1e-4, 1}, {0, 0.2, 1e-4, 1}})
    history.append(s);
  auto run = history.run_changes(0, 5, 1e-3);
  EXPECT_EQ(run.first, (std::vector<int>{1, 2, 0, 0}));
  EXPECT_EQ(run.last, (std::vector<int>{3, 2, 0, 0}));
  // Counted from the run's own first station, which changes nothing itself.
  run = history.run_changes(2, 5, 1e-3);
  EXPECT_EQ(run.first, (std::vector<int>{1, 0, 0, 0}));
  EXPECT_EQ(run.last, (std::vector<int>{1, 0, 0, 0}));
  // Without a floor, the drift is a change.
  EXPECT_EQ(history.run_changes(0, 5, 0).last[2], 2);
  EXPECT_THROW(history.run_changes(3, 3, 1e-3), std::out_of_range);
  EXPECT_THROW(history.run_changes(0, 6, 1e-3), std::out_of_range);
}

namespace {

// A 16 x 16 x 2 plate whose top layer the tool crosses row by row, `per_station` elements a station.
ActivityHistory sweep(const drom::fem::Mesh& mesh, int per_station) {
  ActivityHistory history(static_cast<std::size_t>(mesh.element_count()));
  std::vector<double> remaining(static_cast<std::size_t>(mesh.element_count()), 1.0);
  std::vector<int> top;
  for (int e = 0; e < mesh.element_count(); ++e)
    if (mesh.centroid(e).z() > 1.0) top.push_back(e);
  for (std::size_t i = 0; i < top.size(); i += static_cast<std::size_t>(per_station)) {
    for (std::size_t j = i; j < std::min(top.size(), i + static_cast<std::size_t>(per_station)); ++j) remaining[static_cast<std::size_t>(top[j])] = 0.3;
    history.append(remaining);
  }
  return history;
}

}  // namespace

TEST(StationSchedule, StationsPerFactorizationFollowTheBlockCostModel) {
  const auto shape = drom::geometry::PartShape::plate(160, 160, 2);
  const auto mesh = drom::fem::make_structured_hex_mesh(shape, {16, 16, 2, 1.0});
  const auto history = sweep(mesh, 2);  // 128 stations of 2 elements
  // A full factorization far dearer than any block: the largest chunk, whose first station is the
  // only full one (the model's own sum, checked at C = 64: 2 chunks, and 0.1 F a station besides).
  const double huge = 1e15;
  auto choice = choose_stations_per_factorization(history, mesh, huge);
  EXPECT_EQ(choice.chunk, 64u);
  ASSERT_EQ(choice.estimates.size(), 7u);
  EXPECT_EQ(choice.estimates.front().first, 1u);
  EXPECT_DOUBLE_EQ(choice.estimates.front().second, 128 * 1.1 * huge);
  EXPECT_NEAR(choice.estimates.back().second, (2 + 128 * 0.1) * huge, 0.01 * huge);
  // Each estimate falls as C grows while blocks stay cheap.
  for (std::size_t i = 1; i < choice.estimates.size(); ++i) EXPECT_LT(choice.estimates[i].second, choice.estimates[i - 1].second);

  // A full factorization so cheap that no block pays (two elements' m = 3 x 32 nodes = 96 dofs, and
  // a chunk of two stations pays only if F + m^3/3 + (m^3/3 + m^3/3) < 2 F, F > 8.8e5): one full
  // factorization a station, every C costing the same (ties go to the smaller C).
  choice = choose_stations_per_factorization(history, mesh, 1e5);
  EXPECT_EQ(choice.chunk, 1u);
  for (const auto& [C, cost] : choice.estimates) EXPECT_DOUBLE_EQ(cost, 128 * 1.1 * 1e5) << C;

  // In between, the growth of m with C bounds the chunk: blocks pay up to some C, not beyond.
  choice = choose_stations_per_factorization(history, mesh, 3e8);
  EXPECT_GT(choice.chunk, 1u);
  EXPECT_LT(choice.chunk, 64u);
  const auto best = std::min_element(choice.estimates.begin(), choice.estimates.end(), [](auto& a, auto& b) { return a.second < b.second; });
  EXPECT_EQ(best->first, choice.chunk);
}
