#pragma once
// The tool as the avoidance sees it (seed 000 §3-4): a cutting part (ball or torus end, with its flute
// length), excluded from the repulsion, and above it the shank and the holder, a revolved profile that
// must stay clear of the check surfaces. Local frame: origin at the pivot (CL: the ball's centre; for a
// torus the centre of its corner circle's plane, on the axis), z along the tool axis towards the spindle.
#include "paths/tool.hpp"

#include <Eigen/Core>

#include <vector>

namespace drom::paths {

// A revolved profile: radius against height above the tool tip, piecewise linear (z increasing).
struct RevolvedProfile {
  std::vector<double> z, radius;  // mm
  double radius_at(double height) const;  // 0 outside [z.front(), z.back()]
  double max_radius() const;
};

struct ToolBody {
  Tool cutter;                 // ball (r = R) or torus (R, r)
  double flute_length = 10;    // mm above the tip: the cutting part, excluded from the repulsion
  double shank_radius = 5;     // mm
  double stick_out = 30;       // mm from the tip to the holder's face (the tool length the seed varies: 20, 30)
  RevolvedProfile holder;      // heights above the holder's face

  // Height of the pivot above the tip (R for a ball, r for a torus).
  double pivot_height() const { return cutter.corner_radius; }
  // The shank+holder profile, heights above the tip (from the flute's end to the holder's top).
  RevolvedProfile body_profile() const;
  double length() const;  // tip to the holder's top
  // Throws InputError when the dimensions are inconsistent (radii ≤ 0, r > R, flutes beyond the stick-out).
  void check() const;
};

// Nodes on the shank+holder skin, local frame (pivot at the origin): `count` random nodes distributed by
// area (the seed's 500), or, when `count` ≤ 0, one per `spacing`² of skin (the seed's ~1 mm skin).
// Deterministic for a given seed.
std::vector<Eigen::Vector3d> tool_skin_nodes(const ToolBody& tool, int count, double spacing, unsigned seed = 2014);
// The shank+holder skin's area (mm²): what `spacing` divides into nodes.
double tool_skin_area(const ToolBody& tool);

// Signed distance from a local point to the cutting part's solid (negative inside): the ball, or the
// torus with its flat bottom, up to the flute length (a cylinder of radius R above).
double cutter_signed_distance(const ToolBody& tool, const Eigen::Vector3d& local);

}  // namespace drom::paths
