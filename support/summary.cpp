#include "support/summary.hpp"

#include "support/atomic_file.hpp"
#include "support/resources.hpp"

#include <fstream>
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

}  // namespace drom
