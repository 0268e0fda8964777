#pragma once
// The sharp edges of a scan, completed (issue 45). A scanner samples faces, not the line where two
// faces meet: the points nearest a sharp crest stand up to half a spacing from it, lower than it by
// that times the flank's slope, and a tool dropped on the points rolls over them and cuts the crest
// off (a ridge at 50° scanned every millimetre lost 0.6 mm). Where the scan shows a crease, the line
// is put back.
//
// A crease. The scan is thinned to cells (geometry/cloud_cells.hpp); where the points within 2.5
// cells stand off their least-squares plane by more than the noise allows, they are split in two
// (along each in-plane direction, and along the direction away from the cell's centroid; the split
// that leaves the least residual), a plane is fitted to each half, and the cell holds a crease when
// both halves are flat to the noise, the planes meet at 15° or more, and their line passes within 1.5
// cells of one of the cell's points. Under noise, a cell that shows nothing is read again over the points
// within 53 noise deviations (where faces meeting at 30° stand a deviation off a quadric), the two
// planes held to leave less than the quadric by five deviations of the residuals' ratio. The line is
// sampled every `spacing` mm across the cell's extent and half a cell beyond.
// Points on a concave crease (the foot of a wall) lie on the surface the ball cannot reach anyway:
// they change nothing. A cloud with no crease gets no point.
#include "geometry/cloud_cells.hpp"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace drom::geometry {

struct Creases {
  std::vector<Eigen::Vector3d> points;  // on the crease lines
  std::vector<int> source;              // per point: a scanned point of the cell it was found in
  std::size_t cells = 0;                // cells found on a crease
  double cell = 0;                      // mm
};

// `noise`: the scan's noise (geometry/cloud_noise.hpp); `spacing`: between the added points (mm).
Creases crease_points(std::span<const Eigen::Vector3d> points, double noise, double spacing);
// On the cells of a survey already made (geometry/cloud_cells.hpp).
Creases crease_points(std::span<const Eigen::Vector3d> points, const ScanSurvey& survey, double noise, double spacing);

}  // namespace drom::geometry
