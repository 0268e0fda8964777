#pragma once
// The FE core on its closed-form case (drom layer): the case's residual stress equilibrated, the intact
// stock solved clamped, then the stock thinned by the pocket depth everywhere, clamped and then free;
// on a plate, the free curvature against the closed form of layer removal (fem/layer_removal.hpp).
// Writes layer.pvd and its .vtu states, and summary.json, into `out`.
#include "case_file/case.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>

namespace drom::offline {

// Returns the summary (summary.json's content). Progress on stderr unless quiet.
nlohmann::json run_layer_check(const case_file::Case& c, const std::filesystem::path& out, bool quiet);

}  // namespace drom::offline
