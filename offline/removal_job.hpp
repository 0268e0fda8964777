#pragma once
// The material each tool station removes, on the case's mesh (drom removal): the remaining fraction of
// every element at every station (removal.h5), frames of the remaining part (removal.pvd), volumes per
// station (volumes.csv), the removed region's surface (removed_surface.vtp), the program
// (toolpath.nc) and summary.json, in `out`.
#include "case_file/case.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>

namespace drom::offline {

// Returns the summary. Progress on stderr unless quiet.
nlohmann::json run_removal(const case_file::Case& c, const std::filesystem::path& out, bool quiet);

}  // namespace drom::offline
