#pragma once
// Generated pocketing toolpaths: a rectangular pocket of constant depth below the stock's top face
// (flat plate, or following a cylindrical panel), cleared one-way, zigzag or by an inward spiral.
#include "geometry/part_shape.hpp"
#include "paths/cutter/tool_assembly.hpp"
#include "levelset/toolpath.hpp"

namespace drom::levelset {

enum class PocketStrategy { OneWay, Zigzag, Spiral };

struct PocketSpec {
  double x_min = 0, y_min = 0, length_x = 0, length_y = 0;  // parametric (u, v), mm
  double depth = 0;                                         // below the top face, mm
};

struct PocketPathSpec {
  PocketStrategy strategy = PocketStrategy::OneWay;
  double stepover = 0;          // mm between passes
  double feed = 10;             // mm/s
  double plunge_feed = 2;       // mm/s
  double clearance = 5;         // safe height above the stock's top, mm
  double chord_tolerance = 0.01;  // mm, for paths that follow a curved surface
  // One-way and zigzag passes leave cusps along the walls they end on; a final contour pass at the
  // tool radius from the walls clears them (standard pocketing practice).
  bool finish_walls = true;
};

// Scallop height h left between passes s apart on a flat floor: h = r - sqrt(r^2 - (s - 2 (R - r))^2 / 4)
// for the corner radius r (ball: r = R). Flat tools leave none while s <= 2R.
double scallop_height(const paths::ToolAssembly& tool, double stepover);
// The stepover that leaves the given scallop height (ball and bull-nose tools).
double stepover_for_scallop(const paths::ToolAssembly& tool, double scallop);

// Tip altitude that puts the tool on the pocket floor without gouging it (3-axis, vertical tool):
// the highest contact over the tool's footprint. Equal to the floor height on a flat plate.
double tool_tip_on_floor(const geometry::PartShape& shape, const paths::ToolAssembly& tool, double floor_t, double u, double v);

// Throws std::invalid_argument when the pocket cannot hold the tool or the stepover is unusable.
Toolpath pocket_toolpath(const geometry::PartShape& shape, const PocketSpec& pocket, const paths::ToolAssembly& tool, const PocketPathSpec& spec);

// The v positions of the passes of a one-way or zigzag pocket (tool centre), first to last.
std::vector<double> pass_positions(const PocketSpec& pocket, const paths::ToolAssembly& tool, double stepover);

}  // namespace drom::levelset
