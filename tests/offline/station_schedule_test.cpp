// The pieces of issue 26's scheduling: station ranges, the balanced blocks dealt to the ranks, and
// the removal history rank 0 hands the others.
#include "offline/activity_history.hpp"
#include "offline/station_schedule.hpp"
#include "support/input_error.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>

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
