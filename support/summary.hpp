#pragma once
// summary.json: every command's key figures, written atomically.
#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

namespace drom {

nlohmann::json machine_info();
void write_summary(const std::filesystem::path& out_dir, const nlohmann::json& summary);

// For the commands that write straight into their folder (the distortion chain: offline, truth,
// run, study, reduce, ...; the others stage theirs, support/run_folder.hpp): before a new run of
// `command` (summary.json's "command") writes anything, the earlier run's summary.json goes first,
// then the files it lists. So a run killed midway never leaves a folder that looks complete, and no
// output of an earlier run stays beside a new one's. Files it does not list (the user's, the caches a
// command keeps under their own key, such as drom run's offline/ and truth/ databases) are left
// alone; a listed path that would leave the folder, or name the folder itself, is ignored, and a
// symbolic link is removed, never followed. A folder holding another command's summary.json (drom
// study into drom run's folder, drom reduce into the database's), or a summary.json drom did not
// write, is refused: InputError naming --out, before anything is removed.
void clear_earlier_run(const std::filesystem::path& out_dir, const std::string& command);

}  // namespace drom
