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
  // A packet whose program the machine cannot run: the rest is written, the run ends with exit 3.
  std::string refused;
  for (const auto& p : s["packets"])
    for (const char* op : {"roughing", "finishing"})
      if (refused.empty() && p.contains(op) && p[op].contains("refused")) refused = p[op]["refused"].get<std::string>();
  if (!refused.empty()) std::fprintf(stderr, "drom copy: no runnable program for a packet: %s; the rest is in %s\n", refused.c_str(), o.out.string().c_str());
  const int code = refused.empty() ? 0 : 3;
  if (o.quiet) return code;
  const auto& g = s["grouping"];
  std::printf("  cloud                 %zu points, %zu with a normal (PCA disagrees by %.2f deg on average)\n", s["cloud_points"].get<std::size_t>(),
              s["normals"]["points"].get<std::size_t>(), s["normals"]["pca_mean_disagreement_deg"].get<double>());
  const auto& scan = s["scan"];
  std::printf("  scan                  %zu points read: %zu not finite and %zu far outliers dropped\n", scan["points_read"].get<std::size_t>(),
              scan["dropped_not_finite"].get<std::size_t>(), scan["dropped_far_outliers"].get<std::size_t>());
  std::printf("  packets               %zu (%s; decided by %s, largest tilt %.0f deg): %.1f %% of the points with a normal covered (%.1f %% of all points kept), %d overlap points, %d re-attached, %d unmachinable\n",
              g["packets"].get<std::size_t>(), g["method"].get<std::string>().c_str(), g["decided_by"].get<std::string>().c_str(), g["largest_tilt_deg"].get<double>(),
              100 * scan["coverage_of_points_with_normal"].get<double>(),
              100 * scan["coverage_of_points_kept"].get<double>(), g["overlap_points"].get<int>(), g["reattached"].get<int>(), g["unmachinable"].get<int>());
  for (std::size_t k = 0; k < s["packets"].size(); ++k) {
    const auto& p = s["packets"][k];
    std::printf("  packet %zu              axis (%.3f, %.3f, %.3f), rotary (%.1f, %.1f) deg, %d points\n", k + 1, p["axis"][0].get<double>(), p["axis"][1].get<double>(),
                p["axis"][2].get<double>(), p["rotary_deg"][0].get<double>(), p["rotary_deg"][1].get<double>(), p["points"].get<int>());
    for (const char* op : {"roughing", "finishing"})
      if (p.contains(op))
        std::printf("    %-9s           %zu points, %.0f mm cut, %.1f s on the machine; deepest into the cloud %.4f mm\n", op, p[op]["path_points"].get<std::size_t>(),
                    p[op]["cutting_length_mm"].get<double>(), p[op]["cycle_time_s"].get<double>(), p[op]["check"]["deepest_mm"].get<double>());
    if (p.contains("finishing") && p["finishing"].contains("floor")) {
      const auto& f = p["finishing"]["floor"];
      std::printf("    finishing floor     %.0f mm2 of surface: passes at least %.0f mm long (these are %.2fx that), %.1f s (the cycle is %.2fx that)\n",
                  f["area_mm2"].get<double>(), f["length_mm"].get<double>(), f["cutting_length_over_floor"].get<double>(), f["time_s"].get<double>(),
                  f["cycle_over_floor"].get<double>());
    }
    for (const char* op : {"roughing", "finishing"})
      if (p.contains(op) && p[op].contains("program_verdict")) {
        const auto& v = p[op]["program_verdict"];
        const auto& d = v["demand_at_programmed_feed"];
        std::printf("    %-9s program   %s; demand over the limits at the programmed feed: velocity %.3gx, acceleration %.3gx, jerk %.3gx%s\n", op,
                    v["runnable"].get<bool>() ? "runnable" : "NOT runnable", d["velocity"]["ratio"].get<double>(), d["acceleration"]["ratio"].get<double>(),
                    d["jerk"]["ratio"].get<double>(), v["slows_down"].get<bool>() ? " (warning: the machine slows down)" : "");
      }
    if (p.contains("error")) std::printf("    error               %s\n", p["error"].get<std::string>().c_str());
  }
  for (const auto& t : s["times"]) std::printf("  %-21s %.2f s wall, %.2f s CPU\n", t["stage"].get<std::string>().c_str(), t["wall_s"].get<double>(), t["cpu_s"].get<double>());
  return code;
}

}  // namespace drom::app
