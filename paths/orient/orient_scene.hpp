#pragma once
// What the collision-free orientation works on: the check surfaces (patches, or triangles from STL)
// with their outward material normals, the part surfaces the cutter finishes (for the gouge check),
// the passes (CL path, surface normal, programmed lead/tilt), and the tool. The seed's cases are built
// here from their parameters (docs/orientation.md documents each geometry):
//   - bump: the Bézier check surface of the seed's Table 4.5 beside a straight pass (§3-3.2);
//   - corner: a 90° pocket corner whose walls encroach differently on the two legs (§3-4.2);
//   - impeller: a hub and 7 blades as B-spline surfaces, iso-parametric passes in each vein (§3-5, §4-3);
//   - panel: the distortion cases' curved panel, its pocket floor finished in 5 axes between the pocket
//     walls and the clamps.
#include "geometry/nurbs_surface.hpp"
#include "paths/orient/axis_dynamics.hpp"
#include "paths/orient/repulsive_field.hpp"
#include "paths/orient/tool_skin.hpp"

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace drom::paths {

struct CheckPatch {
  std::string name;
  geometry::NurbsSurface surface;
  bool flip = false;  // the material's outward normal is −(S_u × S_v)
};

struct OrientScene {
  std::string name, description;
  std::vector<CheckPatch> check_patches;
  TriangleSoup check_mesh;                               // check surfaces given as triangles (STL), outward by winding
  std::vector<CheckPatch> part_surfaces;                 // finished by the cutter (gouge check only)
  std::vector<FramedPath> passes;                        // CL = the tool's pivot
  std::vector<std::string> pass_names;
  ToolAssembly tool;
  // Where the scene's frame sits on the machine's table (machine/'s setup.part_origin: table point =
  // scene point + part_origin): the scenes are mounted as a setter would, the panel centred on C.
  Eigen::Vector3d part_origin = Eigen::Vector3d::Zero();
};

// The check surfaces as point obstacles at `spacing` (binned at cell `cell`, the influence radius).
ObstacleCloud scene_obstacles(const OrientScene& scene, double spacing, double cell);
// The check surfaces as triangles at about `step` (for the distance field).
TriangleSoup scene_check_triangles(const OrientScene& scene, double step);

// A pass on a part surface along the iso-line v = const (u from u0 to u1), `count` CL points on the
// offset S + (pivot height) n... exactly: CL = S + R n for a ball (the pivot is the ball's centre), and
// S + r n for a torus (the corner circle's plane centre lies at (R − r) from the corner centre: a torus
// pivot keeps the contact only where the axis follows n; the gouge check reports the rest).
// `lead_in` (mm): a straight approach along the start's tangent before the surface, so the axis can turn
// away from obstacles before the cut begins (the model cannot recover a pose that starts in collision).
FramedPath iso_pass(const geometry::NurbsSurface& surface, bool flip, double v, double u0, double u1, int count, double pivot_offset, double roll,
                    double pitch, double lead_in = 0);

// Each scene is drawn for a tool: the passes are placed at its pivot (CL = S + R n for a ball). `tool`
// replaces the scene's own (default_tool) when set, so a case's [tool] moves the CL points with it.
struct BumpOptions {
  double lateral = 8;     // mm: the pass's distance in y from the bump's base line y = 0
  double spacing = 3;     // obstacle mesh (mm); the seed's 3 and 1 mm
  std::optional<ToolAssembly> tool;
};
ToolAssembly default_tool(const BumpOptions& o);
OrientScene bump_scene(const BumpOptions& o);

struct CornerOptions {
  double stick_out = 20;  // the seed's 20 and 30 mm tools
  double roll = -0.3;     // θf,prog (rad)
  std::optional<ToolAssembly> tool;
};
ToolAssembly default_tool(const CornerOptions& o);
OrientScene corner_scene(const CornerOptions& o);

struct ImpellerOptions {
  int blades = 7;
  double hub_inlet_radius = 45, hub_outlet_radius = 110;  // mm
  double hub_inlet_height = 25;                           // hub z at the inlet (0 at the outlet)
  double blade_height_inlet = 32, blade_height_outlet = 18;  // mm above the hub
  double wrap = 0.35;        // rad of blade wrap from inlet to outlet
  double lean = 0.2;         // rad: the blade leans over the vein (rake), rising by height·tan(lean)
  double lead_in = 20;       // mm of approach before the inlet
  double thickness = 3;      // mm
  double v_first = 0.2, v_last = 0.8, v_step = 0.01;  // the seed's passes in each vein
  double point_spacing = 0.5;  // mm between CL points along a pass
  int veins = -1;            // -1: all
  double lead = 0.1745;      // rad of θt,prog (pitch along the feed): a ball does not cut on its tip
  std::optional<ToolAssembly> tool;
};
ToolAssembly default_tool(const ImpellerOptions& o);
OrientScene impeller_scene(const ImpellerOptions& o);
// The scene's size before it is built (a case must not ask for a scene no machine holds): passes per
// vein, and CL points in all (the veins are rotations of each other: one vein's passes are counted).
std::size_t impeller_passes_per_vein(const ImpellerOptions& o);
double impeller_cl_points(const ImpellerOptions& o);
// The vein's hub patch, blade k's two sides (pressure, suction), as B-spline surfaces.
geometry::NurbsSurface impeller_hub_patch(const ImpellerOptions& o, int vein);
geometry::NurbsSurface impeller_blade_side(const ImpellerOptions& o, int blade, int side);

struct PanelOptions {
  double outer_radius = 1750, length = 450, width = 450, thickness = 4.5;
  double pocket = 300, depth = 3;
  double clamp_height = 50, clamp_reach = 70;  // clamp jaws on the faces x = 0 and x = length
  double stepover = 30;   // mm between passes on the floor
  double lead = 0.1745;   // rad
  std::optional<ToolAssembly> tool;
};
ToolAssembly default_tool(const PanelOptions& o);
OrientScene panel_scene(const PanelOptions& o);

}  // namespace drom::paths
