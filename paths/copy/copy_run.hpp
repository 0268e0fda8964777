#pragma once
// `drom copy CLOUD`: a scanned part copied by 3+2 machining of its cloud (paths/copy/cloud_copy.hpp) and
// written out: the normals as PLY, the points with their packet, visibility count and overlap flag
// (VTK and PLY), per packet its roughing and finishing paths (VTK, drop and part frames), CL data and
// 3+2 G-code through machine/'s post-processor, and summary.json (stages' times, packets, coverage,
// gaps, the whole-tool path checks, the predicted cycle times). docs/outputs.md lists every file.
#include <nlohmann/json.hpp>

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace drom::paths {

struct CopyRunOptions {
  std::filesystem::path cloud;                    // XYZ/CSV or PLY
  std::optional<std::filesystem::path> settings;  // a settings file (docs/case-files.md, "drom copy"); none: the defaults
  std::vector<std::string> overrides;             // "key=value" on the settings
  std::string tool;                               // finishing tool ("ball:6", "torus:10:2", "flat:8"); empty: the settings'
  std::string machine;                            // a machine file or shipped name; empty: the settings'
  std::filesystem::path out = "out/copy";
  bool quiet = false;
};

// Runs the pipeline and writes its outputs; returns the summary. Throws InputError on bad input.
nlohmann::json run_copy(const CopyRunOptions& options);

}  // namespace drom::paths
