#pragma once
// The holes of a scan, filled (issue 45). A ball dropped on points rests on them and dips between:
// by rho^2 / 2r where the nearest points stand rho from its lowest point (r its corner radius). On a
// scan with gaps wider than sqrt(r Tu) (a coarse grid, points at random, a slope seen from above) the
// tool cuts below the surface the points describe by more than the tolerance (0.44 mm on a plate
// scanned at random every 0.9 mm, with a ball D6).
//
// Each point's neighbourhood (its 16 nearest) is fitted with a quadric in the frame of its
// least-squares plane (a moving least-squares surface, which also averages the noise away; two planes
// at a sharp crease: geometry/cloud_cells.hpp's LocalSurface), and the
// part of that plane nearer this point than any neighbour (its Voronoi cell) is sampled on a grid of
// `hole` sqrt(2) mm: a grid node farther than `hole` from every point, and surrounded by the
// neighbours (no angular gap of 180° around it: no point beyond the scan's rim), gets a point on the
// quadric. Afterwards no spot of the scanned surface is farther than about `hole` from a point.
// Points added are never a gouge: at worst, where the quadric bulges over a crease, the tool stays a
// little higher.
#include "geometry/cloud_cells.hpp"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace drom::geometry {

struct FilledHoles {
  std::vector<Eigen::Vector3d> points;  // added
  std::vector<int> source;              // per added point: the scan's point whose neighbourhood made it
  double spacing = 0, spacing_p90 = 0;  // the scan's typical spacing and its 90th percentile (mm)
  bool needed = false;                  // false: the scan is dense enough (by its spacing, or a sample), not gone through whole
};

// `hole`: the widest gap radius allowed (mm). Scans whose 90th-percentile spacing is under hole / 1.5
// are left as they are without looking further, and so are those where 4 000 points drawn with a fixed
// seed border no hole (a hole touching fewer than about one point in 4 000 can escape that look). `noise` (the scan's, geometry/cloud_noise.hpp): the
// quadric through noisy points is itself uncertain there by noise sqrt(x^T (A^T A)^-1 x) (about
// noise sqrt(6 / 16) amid its neighbours, more towards their edge), so each point is put that many
// times above and below it (one of them inside the part, where it changes nothing) that the lowest
// of the neighbourhoods that fill stays above the surface (safe_lift_deviations: 3 deviations, 3.9
// when 2 000 neighbourhoods fill): the tool stays on the
// safe side of what the scan cannot tell. Where the fit would extrapolate far (that ratio above 4), no
// point is put.
FilledHoles fill_holes(std::span<const Eigen::Vector3d> points, double hole, double noise = 0);
// With a survey already made (geometry/cloud_cells.hpp).
FilledHoles fill_holes(std::span<const Eigen::Vector3d> points, const ScanSurvey& survey, double hole, double noise = 0);

}  // namespace drom::geometry
