#pragma once
// The cross-section of a tool swept along a pass, and what one pass keeps within the scallop bound
// on either side of it. Straight along the pass, a torus (the balls of radius r centred on its tube
// circle) sweeps the union of disks of radius r centred on that circle projected along the pass; a
// ball, one disk of radius R. Eq. 1.5 (the seed's effective radius) replaces that profile by its
// osculating circle at the contact, which is exact for the ball and, for a torus fed obliquely to
// the slope, neither symmetric nor right at a step's distance: on a 30 deg plane fed 40 deg off its
// level lines, eq. 1.5's half step leaves 0.0127 mm against sh = 0.01 (tests/paths/finish/passes_test.cpp).
#include "paths/cutter/tool.hpp"

#include <Eigen/Core>

#include <vector>

namespace drom::paths {

// How far (mm across, on the side `across` points to) one pass alone keeps the scallop within
// `scallop`: where the first and last planes of a zone go. Exact for both tools: the pass's
// tool, swept along the pass tangent `along`, has for cross-section the lower envelope of disks of
// radius r centred on the tube centre circle projected along the tangent (a ball: one disk of
// radius R); the ground across is its osculating circle (`curvature`, > 0 concave). For a ball that is
// half the two-pass step; for a tilted torus the two sides differ, and on the uphill side the half
// step leaves up to 12 % more than sh.
double one_pass_reach(const Tool& tool, const Eigen::Vector3d& normal, const Eigen::Vector3d& axis, const Eigen::Vector3d& along, const Eigen::Vector3d& across,
                      double curvature, double scallop);


// The reach of the torus's two sides on level ground, tabulated once per tool and sh over the
// slope s (against the axis, 1 deg steps) and the azimuth beta of the normal's part across the
// axis, measured from the feed towards m = axis x feed (2 deg steps; the profile is the same at
// pi - beta, and its sides swap at -beta); the smallest of the four neighbouring entries.
struct SideReach {
  double minus = 0, plus = 0;  // mm across, on the sides towards -m and +m
};
class SweptProfileTable {
 public:
  SweptProfileTable(const Tool& tool, double scallop);
  SideReach reach(double slope, double beta) const;

 private:
  int slopes_ = 0, azimuths_ = 0;
  std::vector<SideReach> table_;  // [slope][azimuth], azimuth in [0, pi/2]
};

// The table of the tool and sh, built on first use and shared (thread-safe).
const SweptProfileTable& swept_profile_table(const Tool& tool, double scallop);

}  // namespace drom::paths
