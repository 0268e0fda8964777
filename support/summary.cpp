#include "support/summary.hpp"

#include "support/atomic_file.hpp"
#include "support/input_error.hpp"
#include "support/resources.hpp"

#include <fstream>
#include <stdexcept>
#include <thread>

namespace drom {

nlohmann::json machine_info() {
  std::string cpu;
  std::ifstream info("/proc/cpuinfo");
  for (std::string line; std::getline(info, line);)
    if (line.rfind("model name", 0) == 0) {
      cpu = line.substr(line.find(':') + 2);
      break;
    }
  return {{"cpu", cpu}, {"hardware_threads", std::thread::hardware_concurrency()}, {"peak_memory_mb", static_cast<double>(peak_memory_bytes()) / 1048576.0}};
}

void write_summary(const std::filesystem::path& out_dir, const nlohmann::json& summary) {
  write_file_atomically(out_dir / "summary.json", summary.dump(2) + "\n");
}

void clear_earlier_run(const std::filesystem::path& out_dir, const std::string& command) {
  namespace fs = std::filesystem;
  const fs::path summary = out_dir / "summary.json";
  std::error_code ec;
  if (!fs::exists(fs::symlink_status(summary, ec))) return;
  const std::string shown = "--out " + out_dir.string();
  nlohmann::json earlier;
  {
    std::ifstream in(summary);
    earlier = nlohmann::json::parse(in, nullptr, false);
  }
  if (!earlier.is_object() || !earlier.contains("command") || !earlier["command"].is_string())
    throw InputError(shown + ": its summary.json is not one drom wrote, and drom " + command + " writes one there: give a folder of its own");
  const std::string other = earlier["command"].get<std::string>();
  if (other != command && other != "drom " + command)
    throw InputError(shown + ": it holds the outputs of drom " + other + " (its summary.json), and drom " + command +
                     " would mix its own with them: give a folder of its own");
  fs::remove(summary, ec);
  if (ec) throw InputError(shown + ": cannot remove the earlier run's summary.json: " + ec.message());
  if (!earlier.contains("files") || !earlier["files"].is_array()) return;
  for (const auto& entry : earlier["files"]) {
    if (!entry.is_string()) continue;
    fs::path relative = fs::path(entry.get<std::string>()).lexically_normal();
    if (!relative.empty() && !relative.has_filename()) relative = relative.parent_path();  // "frames/": the entry itself, never through a link
    if (relative.empty() || relative.is_absolute() || relative == "." || *relative.begin() == "..") continue;
    fs::remove_all(out_dir / relative, ec);  // a link is removed, not followed
    if (ec) throw InputError(shown + ": cannot remove the earlier run's " + relative.string() + ": " + ec.message());
  }
}

}  // namespace drom
