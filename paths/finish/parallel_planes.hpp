#pragma once
// Parallel-plane finishing passes over one zone (Herraz ch. 1-2): each pass is the intersection of
// the zone with a plane containing the tool axis; the next plane is placed by the worst point of
// the current pass (the smallest step that keeps the scallop bound there). The fast variant
// intersects the planes with the machining mesh's iso-parametric lines (the seed's method for every
// result); the exact variant (exact_passes.hpp) puts the points on the surface by Newton's method.
#include "paths/finish/machining_mesh.hpp"
#include "paths/finish/swept_profile.hpp"
#include "paths/cutter/tool.hpp"

#include <Eigen/Core>

#include <limits>
#include <vector>

namespace drom::paths {

// How the step between planes is found, and where the first and last planes go.
enum class StepoverModel {
  // The seed's, as reconstructed (docs/finishing.md): eq. 2.3 with eq. 1.5's effective radius; the
  // next plane placed by the step at the pass's point of least effective radius (for a ball, where
  // all tie, the last of them along the feed); the first plane half a step inside the zone, then
  // planes while they still cut it. Reproduces the seed's tables; does not keep the bound everywhere.
  seed,
  // Eq. 2.3 at every point; the next plane placed by the smallest step over the current pass and the
  // next one; the first plane half a step inside the zone and the last half a step from its far edge.
  flat,
  // The same with the exact step on curved ground (curved_stepover): keeps the scallop bound.
  curved,
};
struct PassSettings {
  Tool tool;
  double scallop = 0.01;  // sh, mm
  StepoverModel stepover = StepoverModel::curved;
  bool zigzag = true;  // else one-way: every pass in the feed direction
  // The tool axis, and the feed direction (unit, perpendicular to the axis), in the part's frame.
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  Eigen::Vector3d feed = Eigen::Vector3d::UnitX();
  // The exact variant (exact_passes.hpp): contact points on the surface, chords within this
  // tolerance (mm); the curved model then keeps the scallop plus the chord deviation within sh.
  bool exact = false;
  double chord_tolerance = 2e-4;
  // The longest run-out (mm of arc) past each end where a pass leaves the zone: onto the
  // neighbouring zone, or past the patch's boundary onto the patch's own polynomials continued. A
  // pass runs on while the zone still lies beside it within a plane step (an edge met obliquely:
  // the material between two pass ends is otherwise reached only by the tools' end caps, and the
  // scallop bound fails there, docs/finishing.md section 5), then one step more. 0: the passes stop
  // at the zone's edge, as the seed's do.
  double run_out = 0;
  // The curved model's torus profile (swept_profile.hpp); plan_passes fills it in.
  const SweptProfileTable* profile = nullptr;
};

// The scallop the curved model's step keeps between two passes: sh, less the chord tolerance in the
// exact variant, whose chords leave that much more. The flat and seed models use eq. 2.3 at sh as
// the seed does (they do not claim the bound on curved ground, docs/finishing.md section 5).
double target_scallop(const PassSettings& settings);

struct PlanePass {
  std::vector<Eigen::Vector3d> cc, normals;  // contact points in travel order, and the machined-side normals there
  double level = 0;             // the plane's offset along axis x feed, mm
  double worst_stepover = 0;    // the smallest step on the surface along the pass, mm
  double spacing = 0;           // the plane step this pass allows, mm
  double worst_effective_radius = 0;
  int plane = 0;                // index of the plane in the zone (several passes share a plane where it crosses the zone more than once)
  double run_out_length = 0;    // mm of contact polyline added past the zone's edges (both ends)
  // Contact points where the ground across the pass is more concave than the tool's trace (the
  // curved model's step is 0 there): the tool cuts into the surface beside them.
  int gouging_contacts = 0;
  Eigen::Vector3d first_gouge = Eigen::Vector3d::Zero();  // the first such contact (part frame), if any
  double reach = std::numeric_limits<double>::infinity();  // for a zone's first and last planes: how far to the zone's edge it alone keeps sh (plane units)
  // Where the contact polyline leaves the zone (surface parameters of its ends before any run-out,
  // in the order of cc as planned), and whether it has ends (not a closed loop).
  Eigen::Vector2d uv_front = Eigen::Vector2d::Zero(), uv_back = Eigen::Vector2d::Zero();
  bool open = false;
};

// The passes over the zone's mesh cells, in machining order (planes in increasing level; several
// segments on one plane in travel order), zigzag alternating direction plane by plane. Empty when
// the zone has no cell.
std::vector<PlanePass> plan_passes(const MachiningMesh& mesh, const std::vector<int>& cells, const PassSettings& settings);

// The step between adjacent passes at one contact point, measured along the surface, and the plane
// spacing it allows; the model of plan_passes, for reports and tests.
struct ContactStep {
  double effective_radius = 0, stepover = 0, spacing = 0, curvature = 0, slope = 0, alpha = 0;
};
ContactStep contact_step(const Eigen::Vector3d& normal, const Eigen::Matrix3d& curvature, const PassSettings& settings);

}  // namespace drom::paths
