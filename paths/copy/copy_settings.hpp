#pragma once
// The settings of `drom copy` (copying a scanned part by 3+2 machining of its cloud, Makki 2009): a
// TOML file whose every key is checked like a case file's (support/toml_reader.hpp), with `--set`
// overrides. Defaults are the seed's improved femur-head run (4-§4): sphere D7 launched along
// +-X, +-Y, +Z on a 0.5 mm grid; 216 directions (10 x 30 degrees); the window [5, 85] degrees; a ball
// D6 on a 53 mm holder 40 mm out, 0.2 mm steps; roughing with a flat D10, 3 x 3 x 2 mm; the
// table-table UCP 710-like machine. Keys: docs/case-files.md ("drom copy").
#include "machine/post_processor.hpp"
#include "paths/copy/cloud_finishing.hpp"
#include "paths/copy/cloud_roughing.hpp"
#include "paths/copy/packets.hpp"
#include "paths/copy/sphere_normals.hpp"
#include "paths/copy/visibility.hpp"

#include <optional>
#include <string>
#include <vector>

namespace drom::paths {

struct CopySettings {
  std::string origin;  // the settings file, or "<defaults>"
  double scale = 1;    // every coordinate of the cloud multiplied by it
  // Points with a NaN or infinite value, and far outliers (geometry/cloud_outliers.hpp): dropped and
  // counted (false), or an error naming the first (true). Key cloud.bad_points = "drop" | "error".
  bool bad_points_are_errors = false;
  SphereLaunchSettings normals;
  bool normals_from_file = false;  // a cloud that carries normals: use them for every point instead of launching spheres
  VisibilitySettings visibility;  // its tool is the finishing tool, its machine set by the caller
  PacketSettings packets;
  CloudFinishingSettings finishing;
  double finishing_feed = 2000;  // mm/min (the hip's finishing)
  bool rough = true;
  CloudRoughingSettings roughing;
  double roughing_feed = 5000;   // mm/min
  std::string machine = "ucp710_like";
  std::vector<std::string> machine_overrides;
  // The [program] table (machine/program_keys.hpp): header, spindle, coolant, clearance, and the
  // finishing tool's number; the roughing tool's is roughing.tool_number.
  machine::PostOptions program;
  int roughing_tool_number = 2;
  std::optional<Eigen::Vector3d> stock_lo, stock_hi;  // part frame; none: the cloud's box grown by stock_margin
  double stock_margin = 5;
  bool stock_base_is_obstacle = true;  // the stock under the part stays: the tool must not enter it
  std::optional<double> stock_base_top;  // z of the base's top face (the table the part stands on); none: the cloud's lowest point
  std::vector<Obstacle> fixtures;
  // Beyond the scan's rim is the part's side, not air (geometry/cloud_rim.hpp): key cloud.rim = "side"
  // (the default) or "open" (nothing is assumed there, as before issue 45). The side goes down to the
  // base, or `side_depth` mm below the rim when that is set (key cloud.side_depth).
  bool rim_is_side = true;
  double side_depth = 0;
  // The scan completed: its creases' lines and points in its holes (key cloud.completion).
  bool completion = true;
};

// The defaults as a TOML text (every key, with comments).
std::string default_copy_settings();

// Reads `text` (a settings file; empty: the defaults) with `overrides` ("key=value"). Throws
// InputError naming the origin, the line and the key.
CopySettings read_copy_settings(const std::string& text, const std::string& origin, const std::vector<std::string>& overrides = {});

}  // namespace drom::paths
