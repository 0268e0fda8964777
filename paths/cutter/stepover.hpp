#pragma once
// The trace a cutter leaves and the step-over that keeps a scallop bound. The seed's formulas
// (Herraz 2021): the torus effective radius (eq. 1.5, after Redonnet et al. 2013) and the
// flat-ground step-over (eq. 2.3); and the exact step-over on curved ground, which the seed
// ignores: two circles of radius R_eff on a circle of radius 1/|kappa| (docs/finishing.md).
#include "paths/cutter/tool.hpp"

namespace drom::paths {

// The radius of the tool's trace at the contact point (seed eq. 1.5): the ball's R; for the torus
// (R - r) cos^2(alpha) / (sin(s) (1 - sin^2(alpha) sin^2(s))) + r, with s the slope against the tool
// axis and alpha the angle between the feed and the steepest-slope direction (both in radians).
// Infinite for a torus on level ground (s = 0) along any direction but alpha = pi/2.
double effective_radius(const Tool& tool, double slope, double alpha);

// The seed's step-over on flat ground (eq. 2.3): 2 sqrt(2 sh R_eff - sh^2).
double flat_stepover(double scallop, double effective_radius);

// The exact step-over, measured along the surface, on ground whose normal curvature across the feed
// is `curvature` (1/mm; > 0 where the surface bends towards the tool, i.e. concave as the tool sees
// it). Convex ground needs a smaller step than eq. 2.3, concave ground allows a larger one; both
// tend to eq. 2.3 as the curvature vanishes. Returns 0 where the ground is more concave than the
// tool's trace (1/curvature <= R_eff + sh): the tool gouges there and no step keeps the bound.
double curved_stepover(double scallop, double effective_radius, double curvature);

// The scallop height two traces of radius R_eff leave `stepover` apart on flat ground (eq. 2.3 inverted); R_eff itself
// once the step reaches 2 R_eff.
double flat_scallop(double stepover, double effective_radius);

// The widest step a torus can take on level ground: its flat bottom plus two corner traces,
// 2 (R - r) + 2 sqrt(2 sh r - sh^2) (seed §2.2.2.1); a ball's eq. 2.3 with R. Eq. 1.5 is a
// second-order model whose radius diverges at s = 0, so the step is capped by this.
double level_ground_stepover(const Tool& tool, double scallop);

}  // namespace drom::paths
