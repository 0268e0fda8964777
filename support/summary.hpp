#pragma once
// summary.json: every command's key figures, written atomically.
#include <nlohmann/json.hpp>

#include <filesystem>

namespace drom {

nlohmann::json machine_info();
void write_summary(const std::filesystem::path& out_dir, const nlohmann::json& summary);

// For the commands that write straight into their folder (the distortion chain: offline, truth,
// run, study, reduce, ...; the others stage theirs, support/run_folder.hpp): before a new run
// writes anything, the earlier run's summary.json goes first, then the files it lists. So a run
// killed midway never leaves a folder that looks complete, and no output of an earlier run stays
// beside a new one's. Files it does not list (the user's, the caches a command keeps under their own
// key, such as drom run's offline/ and truth/ databases) are left alone; listed paths that would
// leave the folder are ignored. A summary.json that is not a drom summary (no "command") is left.
void clear_earlier_run(const std::filesystem::path& out_dir);

}  // namespace drom
