#include "support/png_plot.hpp"

#include "support/atomic_file.hpp"
#include "support/png_plot_script.hpp"

#include <nlohmann/json.hpp>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <cerrno>
#include <csignal>

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

namespace drom {

namespace {

nlohmann::json finite(const std::vector<double>& v) {
  nlohmann::json a = nlohmann::json::array();
  for (double d : v) a.push_back(std::isfinite(d) ? nlohmann::json(d) : nlohmann::json(nullptr));  // gaps in the line
  return a;
}

// python3 script spec png, as a child that dies with drom: a drom killed mid-plot (SIGKILL) must not
// leave a plotter writing into its folder after it (docs/robustness.md). The exit status, -1 if none.
int run_plotter(const std::filesystem::path& script, const std::filesystem::path& spec, const std::filesystem::path& png) {
  const pid_t parent = ::getpid();
  const pid_t child = ::fork();
  if (child < 0) return -1;
  if (child == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(1);  // the parent died before the line above
    const int null = ::open("/dev/null", O_WRONLY);
    ::dup2(null, 1), ::dup2(null, 2);
    ::execl("/usr/bin/python3", "python3", script.c_str(), spec.c_str(), png.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  int status = 0;
  while (::waitpid(child, &status, 0) < 0 && errno == EINTR) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

bool write_png_plot(const std::filesystem::path& png, const PlotSpec& spec) {
  static const bool available = std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") == 0;
  if (!available) return false;
  nlohmann::json j;
  j["title"] = spec.title;
  j["x_label"] = spec.x_label;
  j["y_label"] = spec.y_label;
  j["log_y"] = spec.log_y;
  j["series"] = nlohmann::json::array();
  for (const auto& s : spec.series) j["series"].push_back({{"name", s.name}, {"x", finite(s.x)}, {"y", finite(s.y)}, {"style", s.style}});
  if (spec.map) {
    const auto& m = *spec.map;
    nlohmann::json rows = nlohmann::json::array();
    for (int r = 0; r < m.ny; ++r)
      rows.push_back(finite(std::vector<double>(m.values.begin() + static_cast<long>(r) * m.nx, m.values.begin() + static_cast<long>(r + 1) * m.nx)));
    j["map"] = {{"x0", m.x0}, {"x1", m.x1}, {"y0", m.y0}, {"y1", m.y1}, {"values", rows}, {"label", m.label}, {"cmap", m.colormap}};
  }
  j["hlines"] = nlohmann::json::array();
  for (const auto& [name, y] : spec.hlines) j["hlines"].push_back({{"name", name}, {"y", y}});
  std::filesystem::create_directories(png.has_parent_path() ? png.parent_path() : std::filesystem::path("."));
  const auto tag = std::to_string(::getpid()) + "_" + std::to_string(reinterpret_cast<std::uintptr_t>(&spec));
  const auto spec_file = std::filesystem::temp_directory_path() / ("drom_plot_" + tag + ".json");
  const auto script_file = std::filesystem::temp_directory_path() / ("drom_plot_" + tag + ".py");
  std::ofstream(spec_file) << j.dump();
  std::ofstream(script_file) << kPlotScript;
  AtomicFile out(png);
  const int rc = run_plotter(script_file, spec_file, out.temporary_path());
  std::filesystem::remove(spec_file);
  std::filesystem::remove(script_file);
  if (rc != 0 || !std::filesystem::exists(out.temporary_path())) return false;
  out.commit();
  return true;
}

}  // namespace drom
