#include "offline/station_schedule.hpp"

#include "fem/elastic_problem.hpp"
#include "support/input_error.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace drom::offline {

namespace {

// A station's solve time taken to grow as the live elements to this power: a sparse Cholesky of a
// plate-like mesh costs n^1.5 under nested dissection (docs/distributed.md; a law, not a fit).
constexpr double kCostExponent = 1.5;

bool parse_index(std::string_view text, std::size_t& value) {
  const auto [end, error] = std::from_chars(text.data(), text.data() + text.size(), value);
  return error == std::errc() && end == text.data() + text.size();
}

}  // namespace

StationRange parse_station_range(std::string_view text, std::size_t stations, const std::string& what) {
  const auto colon = text.find(':');
  StationRange r{0, stations};
  const auto left = text.substr(0, colon), right = colon == std::string_view::npos ? std::string_view() : text.substr(colon + 1);
  const bool ok = colon != std::string_view::npos && (left.empty() || parse_index(left, r.first)) && (right.empty() || parse_index(right, r.last));
  if (!ok) throw InputError(what + " " + std::string(text) + ": expected a:b, stations a to b - 1 (either may be left out: a: or :b)");
  if (r.first >= r.last || r.last > stations)
    throw InputError(what + " " + std::string(text) + ": the job has stations 0:" + std::to_string(stations) + "; a:b needs 0 <= a < b <= " +
                     std::to_string(stations));
  return r;
}

std::string to_string(const StationRange& r) { return std::to_string(r.first) + ":" + std::to_string(r.last); }

std::vector<double> station_costs(const ActivityHistory& history) {
  std::vector<double> costs(history.stations());
  std::vector<double> fractions;
  for (std::size_t k = 0; k < history.stations(); ++k) {
    history.advance(k, fractions);
    const auto live = std::count_if(fractions.begin(), fractions.end(), [](double a) { return a >= fem::ElasticProblem::kMinVolumeFraction; });
    costs[k] = std::pow(static_cast<double>(live) / static_cast<double>(std::max<std::size_t>(1, history.elements())), kCostExponent);
  }
  return costs;
}

std::vector<double> calibrated_costs(const std::vector<double>& law, const std::vector<double>& measured_seconds) {
  if (measured_seconds.size() != law.size()) throw std::invalid_argument("calibrated_costs: one measured time (or 0) per station");
  std::vector<std::size_t> known;  // measured stations whose law gives a ratio
  for (std::size_t k = 0; k < law.size(); ++k)
    if (measured_seconds[k] > 0 && law[k] > 0) known.push_back(k);
  if (known.empty()) return law;
  auto ratio = [&](std::size_t k) { return measured_seconds[k] / law[k]; };
  std::vector<double> costs(law.size());
  std::size_t next = 0;  // the first known station at or after k
  for (std::size_t k = 0; k < law.size(); ++k) {
    while (next < known.size() && known[next] < k) ++next;
    if (measured_seconds[k] > 0) {
      costs[k] = measured_seconds[k];
    } else if (next == 0) {
      costs[k] = law[k] * ratio(known.front());
    } else if (next == known.size()) {
      costs[k] = law[k] * ratio(known.back());
    } else {
      const std::size_t before = known[next - 1], after = known[next];
      const double t = static_cast<double>(k - before) / static_cast<double>(after - before);
      costs[k] = law[k] * ((1 - t) * ratio(before) + t * ratio(after));
    }
  }
  return costs;
}

std::vector<ChunkTask> chunk_tasks(std::size_t stations, std::size_t chunk, const std::function<bool(std::size_t)>& wanted,
                                   const std::vector<double>& costs) {
  std::vector<ChunkTask> tasks;
  for (std::size_t first = 0; first < stations; first += chunk) {
    const std::size_t end = std::min(stations, first + chunk);
    std::size_t last = first;
    for (std::size_t k = first; k < end; ++k)
      if (wanted(k)) last = k + 1;
    if (last == first) continue;
    tasks.push_back({first, last, std::accumulate(costs.begin() + static_cast<std::ptrdiff_t>(first), costs.begin() + static_cast<std::ptrdiff_t>(last), 0.0)});
  }
  return tasks;
}

std::vector<std::vector<ChunkTask>> deal_blocks(const std::vector<ChunkTask>& tasks, int ranks, double root_extra) {
  // Greedy filling up to a capacity: blocks in order, each closed when the next task would overflow
  // it. The smallest capacity that needs no more than `ranks` blocks, by bisection.
  auto fill = [&](double capacity) {
    std::vector<std::vector<ChunkTask>> blocks(1);
    double load = root_extra;
    for (const auto& t : tasks) {
      // A block holds at least one task, unless rank 0's own work alone already fills block 0.
      if (load + t.cost > capacity && (load > 0 || !blocks.back().empty())) {
        blocks.emplace_back();
        load = 0;
      }
      blocks.back().push_back(t);
      load += t.cost;
    }
    return blocks;
  };
  double low = 0, high = root_extra;
  for (const auto& t : tasks) low = std::max(low, t.cost), high += t.cost;
  low = std::max(low, root_extra);
  for (int i = 0; i < 100 && high - low > 1e-12 * high; ++i) {
    const double mid = 0.5 * (low + high);
    (static_cast<int>(fill(mid).size()) <= ranks ? high : low) = mid;
  }
  auto blocks = fill(high);  // high always fits: at the start, everything in block 0
  if (static_cast<int>(blocks.size()) > std::max(ranks, 1)) throw std::logic_error("deal_blocks: more blocks than ranks");
  blocks.resize(static_cast<std::size_t>(std::max(ranks, 1)));
  return blocks;
}

ChunkChoice choose_stations_per_factorization(const ActivityHistory& history, const fem::Mesh& mesh, double full_flops) {
  constexpr double kOverhead = 0.1;
  const std::size_t ns = history.stations();
  ChunkChoice choice;
  double best = 0;
  for (std::size_t C = 1; C <= 64; C *= 2) {
    double total = 0;
    for (std::size_t first = 0; first < ns; first += C) {
      const std::size_t last = std::min(ns, first + C);
      const double len = static_cast<double>(last - first);
      if (C == 1) {
        total += len * (1 + kOverhead) * full_flops;
        continue;
      }
      const auto plan = fem::ElasticProblem::plan_block(mesh, history.run_changes(first, last, fem::ElasticProblem::kMinVolumeFraction));
      const double m = static_cast<double>(plan.dofs.size());
      if (fem::ElasticProblem::block_pays(plan, full_flops))
        total += full_flops + m * m * m / 3 + plan.refactorization_flops + len * kOverhead * full_flops;
      else
        total += len * (1 + kOverhead) * full_flops;
    }
    choice.estimates.emplace_back(C, total);
    // Only a real gain moves to a larger C: where no block pays, every C sums the same costs.
    if (C == 1 || total < best * (1 - 1e-9)) best = total, choice.chunk = C;
  }
  return choice;
}

}  // namespace drom::offline
