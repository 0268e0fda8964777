#include "support/summary.hpp"

#include "support/atomic_file.hpp"
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

void clear_earlier_run(const std::filesystem::path& out_dir) {
  namespace fs = std::filesystem;
  const fs::path summary = out_dir / "summary.json";
  std::error_code ec;
  if (!fs::is_regular_file(summary, ec)) return;
  nlohmann::json earlier;
  {
    std::ifstream in(summary);
    earlier = nlohmann::json::parse(in, nullptr, false);
  }
  if (!earlier.is_object() || !earlier.contains("command")) return;  // not a drom summary: not ours to clear
  fs::remove(summary, ec);
  if (ec) throw std::runtime_error("cannot remove " + summary.string() + ", the earlier run's: " + ec.message());
  if (!earlier.contains("files") || !earlier["files"].is_array()) return;
  for (const auto& entry : earlier["files"]) {
    if (!entry.is_string()) continue;
    const fs::path relative = fs::path(entry.get<std::string>()).lexically_normal();
    if (relative.empty() || relative.is_absolute() || *relative.begin() == "..") continue;
    fs::remove_all(out_dir / relative, ec);
  }
}

}  // namespace drom
