#pragma once
// One station of a case's machining as a CalculiX input deck (drom offline --export-ccx STATION),
// with drom's own answer for the same station beside it: the comparison of answers and times that
// anyone with ccx can repeat (docs/benchmarks.md, issue 28).
//
// The station is solved as drom offline sees it: the case's mesh, clamps, toolpath and removal, the
// stock equilibrated 3-2-1 under one stress profile (the case's [stress] for drom offline, the real
// part's [truth] for drom truth) and its clamped response after the station's removal. Written to
// `out`: station_<k>.inp (fem/calculix_deck.hpp), station_<k>_drom.csv (node,ux,uy,uz: drom's u,
// full factorization), and summary.json. Run `ccx -i station_<k>` in `out`; its station_<k>.dat
// holds ccx's u of every node.
#include "case_file/case.hpp"
#include "fem/calculix_deck.hpp"
#include "offline/offline_job.hpp"

#include <nlohmann/json.hpp>

#include <Eigen/Core>

#include <cstddef>
#include <filesystem>

namespace drom::offline {

struct CalculixExport {
  std::filesystem::path deck, drom_csv;
  std::size_t station = 0, stations = 0;
  fem::CalculixDeckStats deck_stats;
  Eigen::VectorXd drom_displacement;  // 3 * node + component, mm
  double drom_solve_seconds = 0;      // assembly, factorization and solve of this station, one profile
  nlohmann::json summary;             // what summary.json holds
};

// Throws InputError for a station outside the case's stations, or a mesh the deck cannot hold.
CalculixExport export_calculix_station(const case_file::Case& c, JobKind kind, std::size_t station, const std::filesystem::path& out);

}  // namespace drom::offline
