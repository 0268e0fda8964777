#pragma once
// Finishing on a cloud (Makki 2009 §2.3, the LURPA inverse Z-buffer): parallel planes in a drop frame
// (passes along X, stepped along Y), zigzag, the tool dropped at every node on the whole cloud (so one
// packet's path never gouges its neighbour, §2.3.7). Beyond the seed:
//   - along a pass, nodes are inserted wherever the straight move between two nodes strays from the
//     tool's dropped height by more than the chord tolerance Tu, checked at points between them (the
//     seed's sag against the cloud in a "restricted zone" it does not define: here the tool's whole
//     footprint, through the drop itself). Below the dropped height is a gouge, above it stock left;
//   - across, the step is set pass by pass from the contacts so that the scallop bound holds where
//     the part is steep (the seed used one step computed on a plane at 45°, and lists an adaptive
//     step as future work): two balls whose centres are d apart leave R - sqrt(R^2 - d^2/4) on a
//     plane, d^2 K / (8 R (K - R)) on ground concave with radius K, less on convex ground; the
//     centres of passes dy apart on a cross slope m are dy sqrt(1 + m^2) apart. The torus uses
//     Herraz's effective radius (paths/cutter/tool.hpp), a flat end mill the staircase dy tan(slope);
//   - nodes with no point under the cutter are gaps: counted, listed, and jumped over at a safe
//     height, never plunged into. The shank and the holder are dropped too (tool_assembly.hpp).
#include "geometry/cloud_bins.hpp"
#include "paths/copy/cloud_area.hpp"
#include "paths/copy/cloud_path.hpp"
#include "paths/cutter/tool_assembly.hpp"

#include <Eigen/Core>

#include <vector>

namespace drom::paths {

enum class TransverseStep {
  fixed,     // the given step everywhere
  seed_45,   // the seed's: the step that keeps the scallop on a plane sloping 45° across the passes
  adaptive,  // set pass by pass from the contacts' slopes (and the concave curvature across)
};

struct CloudFinishingSettings {
  ToolAssembly tool;
  double longitudinal_step = 0.2;  // pl: the node grid along a pass, mm
  double chord_tolerance = 0.005;  // Tu, mm
  double scallop = 0.005;          // hc, mm
  TransverseStep transverse = TransverseStep::adaptive;
  double transverse_step = 0.2;    // pt for `fixed`, mm
  double smallest_step = 0;        // adaptive: the step never falls below this (mm); 0: 5 % of the level-ground step
  // Contacts steeper than this (degrees between their normal and the axis) do not set the step: the
  // cloud's border seen from beside it, or walls beyond the tool window (another packet's).
  double steepest = 80;
  bool zigzag = true;
  double clearance = 2;            // mm above everything under a retract
  double approach = 0.5;           // mm above a cut's first node where the feed starts
  double check_spacing = 0;        // mm between the chord tests along a move; 0: half the longitudinal step
  double shortest_move = 0;        // no node inserted closer than this to another (mm); 0: 1/16 of the longitudinal step
  // A link between two cuts longer than this is a retract, shorter ones are fed straight when the
  // tool stays at or above its dropped height all along (mm; 0: 5 level-ground steps, at least 2 mm).
  double longest_link = 0;
  // The bins' points from this index on are not the scan (the part's side below its rim, the stock's
  // base, fixtures): a node whose cutter rests on one of them finishes nothing and is a gap, so the
  // tool never follows the assumed side down. -1: every point is the scan.
  int scan_points = -1;
  // The scan's noise (standard deviation, mm; geometry/cloud_noise.hpp): a move may stay above the
  // dropped height by Tu + 3 noise (stock the noise hides), never below it by more than Tu.
  double noise = 0;
};

struct CloudFinishing {
  CloudPath path;                       // drop frame
  int passes = 0;
  long long nodes = 0;                  // grid nodes inside the area
  long long inserted = 0;               // nodes the chord test added
  long long unresolved = 0;             // shortest moves still dipping more than Tu below the dropped height: taken round the corner
  double unresolved_worst = 0;          // by how much at most, mm
  long long stepped = 0;                // of the moves, those taken round the corner (up, across, down) at a step no chord resolves
  long long gaps = 0;                   // inside nodes with no scanned point under the cutter (nothing, or the side, base or a fixture)
  long long lifted = 0;                 // nodes where the shank or the holder, not the cutter, set the height
  long long below_bound = 0;            // contacts where even the smallest step exceeds the scallop bound
  long long steeper = 0;                // contacts steeper than `steepest`, which did not set the step
  double smallest_step = 0, largest_step = 0, mean_step = 0;  // between consecutive passes, mm
  int retracts = 0, links = 0;
  std::vector<Eigen::Vector2d> gap_nodes;  // drop frame XY
  std::vector<double> levels;              // each pass's Y
};

// The largest pass spacing (mm, along Y of the drop frame, passes along X) that keeps the scallop at
// a contact with this normal (drop frame), `concave_curvature` being the centres' surface curvature
// across the passes (1/mm, > 0 concave; ignored <= 0). Infinite for a flat end mill on level ground
// (capped by the caller).
double transverse_spacing(const Tool& cutter, double scallop, const Eigen::Vector3d& normal, double concave_curvature = 0);
// The step on level ground: the adaptive step's cap, and the fixed settings' default.
double level_ground_spacing(const Tool& cutter, double scallop);

// `bins`: the whole cloud in the drop frame (with the fixture, if any: nothing it holds is cut into).
// Throws InputError when the area is empty or no node of it has a point under the cutter (the area
// asked for misses the cloud), and std::invalid_argument on bad settings.
CloudFinishing plan_cloud_finishing(const geometry::CloudBins& bins, const CloudArea& area, const CloudFinishingSettings& settings);

// The height above which the assembly clears every point under a straight traverse from a to b
// (drop frame XY), plus `clearance`.
double traverse_height(const geometry::CloudBins& bins, const ToolAssembly& tool, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double clearance);

}  // namespace drom::paths
