#pragma once
// summary.json: every command's key figures, written atomically.
#include <nlohmann/json.hpp>

#include <filesystem>

namespace drom {

nlohmann::json machine_info();
void write_summary(const std::filesystem::path& out_dir, const nlohmann::json& summary);

}  // namespace drom
