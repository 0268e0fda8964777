#pragma once
// The tool as the avoidance sees it (seed 000 §3-4): the cutting part (ball or torus end, up to its
// flute length) is excluded from the repulsion; above it the shank and the holder, a revolved profile
// that must stay clear of the check surfaces. The tool is the one cutter model's assembly
// (paths/cutter/tool_assembly.hpp). Local frame: origin at the pivot (the ball's centre; for a torus
// the centre of its corner circle's plane, on the axis), z along the tool axis towards the spindle.
#include "paths/cutter/tool_assembly.hpp"

#include <Eigen/Core>

#include <vector>

namespace drom::paths {

// The shank+holder profile, heights above the tip (from the flutes' end to the holder's top).
RevolvedProfile body_profile(const ToolAssembly& tool);

// Throws InputError when the assembly cannot be an avoidance's tool: radii ≤ 0, r > R, no corner (a
// flat end mill has no pivot), flutes below the corner or beyond the gauge length, a holder profile
// that does not start at its face or goes down.
void check_avoidance_tool(const ToolAssembly& tool);

// Nodes on the shank+holder skin, local frame (pivot at the origin): `count` random nodes distributed by
// area (the seed's 500), or, when `count` ≤ 0, one per `spacing`² of skin (the seed's ~1 mm skin).
// Deterministic for a given seed.
std::vector<Eigen::Vector3d> tool_skin_nodes(const ToolAssembly& tool, int count, double spacing, unsigned seed = 2014);
// The shank+holder skin's area (mm²): what `spacing` divides into nodes.
double tool_skin_area(const ToolAssembly& tool);

// Signed distance from a local point (pivot frame) to the cutting part's solid (negative inside).
double cutter_signed_distance(const ToolAssembly& tool, const Eigen::Vector3d& local);

}  // namespace drom::paths
