#pragma once
// A cutter on its holder: the cutting part up to the flute length, the shank above it and the holder
// from the gauge length (tip to the holder's face) up, one solid of revolution about the tool axis.
// Everyone who asks where the tool is asks this one model:
//   - levelset/ removes what the cutting part sweeps (its signed distance, exact at the surface);
//   - the cloud copy drops the whole profile on a cloud (profile_height: the lowest point of the
//     assembly at radius rho; Makki's digest §2.3) and checks shank and holder against it;
//   - the orientation keeps the shank and holder clear of the check surfaces and the cutting part out
//     of the part (its skin nodes and signed distance, paths/orient/tool_skin.hpp).
#include "paths/cutter/tool.hpp"

#include <string>
#include <vector>

namespace drom::paths {

// A revolved profile: radius against height, piecewise linear (heights not decreasing; a repeated
// height is a step, a flat annulus).
struct RevolvedProfile {
  std::vector<double> z, radius;  // mm
  static RevolvedProfile cylinder(double radius, double height) { return {{0, height}, {radius, radius}}; }
  // A cylinder reaching up without end (the cloud copy's holder: the spindle nose above it is wider
  // still); none for a radius <= 0.
  static RevolvedProfile endless_cylinder(double radius);
  double radius_at(double height) const;  // 0 outside [z.front(), z.back()]
  double max_radius() const;              // 0 when empty
  bool empty() const { return z.empty(); }
};

struct ToolAssembly {
  Tool cutter;
  double flute_length = 0;  // tip to the top of the cutting part, mm (0: 2 R)
  double shank_radius = 0;  // mm (0: the cutter's radius)
  double gauge_length = 0;  // tip to the holder's face, mm (the stick-out; 0: no holder)
  RevolvedProfile holder;   // heights above the holder's face; empty: no holder

  // The removal's tools (levelset/): a cutter with its flutes, nothing above them.
  static ToolAssembly flat(double radius, double flute_length) { return {Tool::flat(radius), flute_length, 0, 0, {}}; }
  static ToolAssembly ball(double radius, double flute_length) { return {Tool::ball(radius), flute_length, 0, 0, {}}; }
  // Throws std::invalid_argument unless 0 < corner radius < radius.
  static ToolAssembly bull_nose(double radius, double corner_radius, double flute_length);

  double flutes() const { return flute_length > 0 ? flute_length : 2 * cutter.radius; }
  double shank() const { return shank_radius > 0 ? shank_radius : cutter.radius; }
  bool has_holder() const { return gauge_length > 0 && holder.max_radius() > 0; }
  double holder_reach() const { return holder.max_radius(); }
  double reach() const;   // the widest radius any part reaches
  double length() const;  // tip to the holder's top (the gauge length plus the holder's height)
  std::string name() const;  // "ball R3, shank D6, holder D53 at 40 mm"

  // The cutting part alone, in the (rho, h) half-plane: its lower profile, its section's radius at
  // height h (0 below the tip and above the flutes), its signed distance (negative inside; the core
  // rectangle grown by r, cut flat at the flutes).
  double bottom_height(double rho) const { return paths::bottom_height(cutter, rho); }
  double section_radius(double h) const;
  double signed_distance(double rho, double h) const;
};

// The whole assembly's lowest point at radius rho >= 0, above the tip; +infinity beyond reach().
// The holder counts from its face up, as wide as its widest section (its own lower profile above the
// face is not modelled: the seed's holders are cylinders).
double profile_height(const ToolAssembly& tool, double rho);

// Where the tool is: its tip and its axis (unit, from the tip into the holder).
struct ToolPose {
  Eigen::Vector3d tip = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
};

// The cutting part's signed distance at x for the tool at `pose`.
double signed_distance(const ToolAssembly& tool, const ToolPose& pose, const Eigen::Vector3d& x);

// Signed distance to the volume the cutting part sweeps while its tip moves along a -> b at constant
// axis: min over the segment of the tool's distance (exact at the surface, convex tools). `tolerance`
// bounds the search along a segment that is not perpendicular to the axis (mm).
double swept_signed_distance(const ToolAssembly& tool, const Eigen::Vector3d& axis, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& x, double tolerance = 1e-6);

// A tool from a short description, as `drom copy --tool` takes it: "ball:D" (diameter D, mm),
// "flat:D", "torus:D:r" (corner radius r). Throws InputError naming `what` (the option) otherwise.
Tool parse_tool(const std::string& text, const std::string& what);

}  // namespace drom::paths
