#pragma once
// The case's part as meshed, with its clamps (drom mesh): mesh.vtu (the clamped nodes and the reduced
// thickness coordinate as point fields) and summary.json, in `out`.
#include "case_file/case.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>

namespace drom::offline {

// Returns the summary.
nlohmann::json write_mesh(const case_file::Case& c, const std::filesystem::path& out);

}  // namespace drom::offline
