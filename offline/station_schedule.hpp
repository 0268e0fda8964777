#pragma once
// Which stations a job (or a slice of it) solves, and how they are dealt out to the ranks: contiguous
// blocks of whole chunks (a chunk is solved in order from a cold start: StationSolvers::chunk), with
// the largest block's estimated cost as small as it can be. A station's cost is estimated from the
// material left at it (docs/distributed.md): late stations have less material and cost less; where
// stations were solved before, their measured times calibrate the estimate.
#include "fem/mesh.hpp"
#include "offline/activity_history.hpp"

#include <cstddef>
#include <functional>
#include <string>
#include <string_view>
#include <vector>

namespace drom::offline {

// Stations first, first + 1, ..., last - 1.
struct StationRange {
  std::size_t first = 0, last = 0;
  bool contains(std::size_t k) const { return k >= first && k < last; }
  std::size_t size() const { return last - first; }
  bool operator==(const StationRange&) const = default;
};

// "a:b" is stations a to b - 1 (Python's slice); "a:" runs to the last station, ":b" starts at 0.
// Throws InputError naming `what` (the option) unless 0 <= a < b <= stations.
StationRange parse_station_range(std::string_view text, std::size_t stations, const std::string& what);
std::string to_string(const StationRange& r);

// A chunk's stations first..last - 1, solved in order from a cold start at `first` (the stations
// before the first one wanted are solved again but not saved), with its estimated cost.
struct ChunkTask {
  std::size_t first = 0, last = 0;
  double cost = 0;
};

// The estimated cost of each station by the cost law, relative (the unit is the intact stock's station).
std::vector<double> station_costs(const ActivityHistory& history);

// The law's costs calibrated on measured solve times (seconds; 0: not measured), which the stations a
// killed run, a resumed run or other slices saved carry: a measured station costs its time; another
// costs the law times the measured-to-law ratio of the nearest measured stations on either side
// (linear in the station's index between them, the nearer one's beyond them). Nothing measured: the law.
std::vector<double> calibrated_costs(const std::vector<double>& law, const std::vector<double>& measured_seconds);

// The chunks of `chunk` stations, out of all the history's stations, that hold a station `wanted`
// says is missing; each ends after its last missing station.
std::vector<ChunkTask> chunk_tasks(std::size_t stations, std::size_t chunk, const std::function<bool(std::size_t)>& wanted,
                                   const std::vector<double>& costs);

// The FE's stations per factorization for a job (solver.stations_per_factorization = "auto"), from
// its removal history: of the candidates 1, 2, 4, ..., 64, the one with the least estimated cost of
// all the stations. Per chunk of C stations with m dofs in its changing elements, in flops (F: a
// full factorization's, fem::ElasticProblem::full_factorization_flops):
//   the block pays (fem::ElasticProblem::block_pays): F + m^3/3 for its first station, the dense
//     refactorizations of the others (fem::BlockPlan::refactorization_flops), kOverhead F each;
//   it does not: (1 + kOverhead) F for every station.
// kOverhead (0.1) stands for what a station costs besides factorizing: assembly, the solves and the
// residual check (measured 0.06 to 0.2 of a full factorization's time, docs/benchmarks.md). Larger C
// spreads the first station's F over more stations but grows m; past the rule's limit a chunk pays
// nothing. Ties go to the smaller C. The estimates are kept, for summary.json.
struct ChunkChoice {
  std::size_t chunk = 1;
  std::vector<std::pair<std::size_t, double>> estimates;  // (C, estimated flops of the whole job)
};
ChunkChoice choose_stations_per_factorization(const ActivityHistory& history, const fem::Mesh& mesh, double full_flops);

// The tasks in `ranks` contiguous blocks, in order, minimising the largest block's cost; block 0
// also carries `root_extra` (rank 0's own work after the stations: the final shape). Blocks may be
// empty when there are fewer tasks than ranks.
std::vector<std::vector<ChunkTask>> deal_blocks(const std::vector<ChunkTask>& tasks, int ranks, double root_extra);

}  // namespace drom::offline
