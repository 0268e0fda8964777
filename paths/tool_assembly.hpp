#pragma once
// A cutter on its holder, as the tool drop and the visibility tests see it: a solid of revolution
// about the tool axis whose lowest point at radius rho stands profile_height(rho) above the tip.
//   - the cutter (Makki's digest §2.3 profiles): ball h = R - sqrt(R^2 - rho^2); flat h = 0; torus
//     (bull-nose, corner r, R0 = R - r) h = 0 for rho <= R0, r - sqrt(r^2 - (rho - R0)^2) beyond;
//   - the shank, from the top of the flutes up, where it is wider than the cutter;
//   - the holder, from the gauge length (tip to holder face, the seed's L = 40 mm) up, radius 53/2 mm
//     in the seed; modelled as reaching up without end (the spindle nose above it is wider still).
// Dropping the whole profile (z_tip = max over points of p_z - profile_height(rho)) gives a height at
// which nothing of the assembly touches the cloud: the path is free of collision by construction.
#include "paths/tool.hpp"

#include <string>

namespace drom::paths {

struct ToolAssembly {
  Tool cutter;                // ball; torus; flat = torus with corner radius 0
  double flute_length = 0;    // tip to the top of the cutting part, mm (0: 2 R)
  double shank_radius = 0;    // mm (0: the cutter's radius)
  double gauge_length = 0;    // tip to the holder's face, mm (0: no holder modelled)
  double holder_radius = 0;   // mm

  double flutes() const { return flute_length > 0 ? flute_length : 2 * cutter.radius; }
  double shank() const { return shank_radius > 0 ? shank_radius : cutter.radius; }
  bool has_holder() const { return gauge_length > 0 && holder_radius > 0; }
  // The widest radius any part reaches.
  double reach() const;
  std::string name() const;  // "ball D6, shank D6, holder D53 at 40 mm"
};

// The cutter's profile h(rho) for 0 <= rho <= R (the cutter's lowest point at that radius, above the tip).
double cutter_height(const Tool& cutter, double rho);
// The whole assembly's, for any rho >= 0; +infinity beyond reach().
double profile_height(const ToolAssembly& tool, double rho);

// A tool from a short description, as `drom copy --tool` takes it: "ball:D" (diameter D, mm),
// "flat:D", "torus:D:r" (corner radius r). Throws InputError naming `what` (the option) otherwise.
Tool parse_tool(const std::string& text, const std::string& what);
bool is_flat(const Tool& cutter);

}  // namespace drom::paths
