// drom copy: a scanned part copied by 3+2 machining of its point cloud (paths/copy/copy_run.hpp).
#include "apps/commands.hpp"
#include "paths/copy/copy_run.hpp"
#include "support/input_error.hpp"

#include <cstdio>

namespace drom::app {

int copy_command(const CommandOptions& options) {
  if (!options.case_path) throw InputError("drom copy needs a cloud: drom copy CLOUD.ply --tool ball:6 --machine ucp710_like");
  paths::CopyRunOptions o;
  o.cloud = *options.case_path;
  o.settings = options.settings;
  o.overrides = options.overrides;
  o.tool = options.tool;
  o.machine = options.copy_machine;
  o.out = options.out;
  o.quiet = options.quiet;
  if (!o.quiet) std::printf("drom copy: %s -> %s\n", o.cloud.string().c_str(), o.out.string().c_str());
  const auto s = paths::run_copy(o);
  if (o.quiet) return 0;
  const auto& g = s["grouping"];
  std::printf("  cloud                 %zu points, %zu with a normal (PCA disagrees by %.2f deg on average)\n", s["cloud_points"].get<std::size_t>(),
              s["normals"]["points"].get<std::size_t>(), s["normals"]["pca_mean_disagreement_deg"].get<double>());
  std::printf("  packets               %zu (%s): %.1f %% covered, %d overlap points, %d re-attached, %d unmachinable\n", g["packets"].get<std::size_t>(),
              g["method"].get<std::string>().c_str(), 100 * g["coverage"].get<double>(), g["overlap_points"].get<int>(), g["reattached"].get<int>(),
              g["unmachinable"].get<int>());
  for (std::size_t k = 0; k < s["packets"].size(); ++k) {
    const auto& p = s["packets"][k];
    std::printf("  packet %zu              axis (%.3f, %.3f, %.3f), rotary (%.1f, %.1f) deg, %d points\n", k + 1, p["axis"][0].get<double>(), p["axis"][1].get<double>(),
                p["axis"][2].get<double>(), p["rotary_deg"][0].get<double>(), p["rotary_deg"][1].get<double>(), p["points"].get<int>());
    for (const char* op : {"roughing", "finishing"})
      if (p.contains(op))
        std::printf("    %-9s           %zu points, %.0f mm cut, %.1f s on the machine; deepest into the cloud %.4f mm\n", op, p[op]["path_points"].get<std::size_t>(),
                    p[op]["cutting_length_mm"].get<double>(), p[op]["cycle_time_s"].get<double>(), p[op]["check"]["deepest_mm"].get<double>());
    if (p.contains("error")) std::printf("    error               %s\n", p["error"].get<std::string>().c_str());
  }
  for (const auto& t : s["times"]) std::printf("  %-21s %.2f s wall, %.2f s CPU\n", t["stage"].get<std::string>().c_str(), t["wall_s"].get<double>(), t["cpu_s"].get<double>());
  return 0;
}

}  // namespace drom::app
