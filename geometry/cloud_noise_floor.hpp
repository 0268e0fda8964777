#pragma once
// A floor above a noisy scan's noise (issue 45). A ball dropped on scanned points rests on the highest
// few under it; where those few all read low (noise along the line of sight), it stands under the true
// surface by about a deviation of the noise: 0.017 mm on a cap scanned under 0.027 mm of noise, 0.046
// mm on a neck under 0.046, where the tolerance is 0.01. Each point's 40 nearest are fitted with a
// quadric (where they make a smooth face: no more residual than 1.3 deviations of the noise and 2 µm),
// or, where they straddle a sharp crease, with two planes (geometry/cloud_cells.hpp's LocalSurface,
// the point's own side's plane counting), and the fit at the point itself is put a safe number of its own deviations above and below it
// (one of them inside the part, where it changes nothing): the fit averages the noise, and the lifted
// point stands above the true surface but where the fit is out by more than that. The tool then rests
// on the higher of the scan and this floor, and leaves stock of about 1.5 noise deviations rather than
// cutting the part by one.
#include "geometry/cloud_cells.hpp"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace drom::geometry {

struct NoiseFloor {
  std::vector<Eigen::Vector3d> points;  // in pairs, above and below each fitted point
  std::vector<int> source;              // per point: the scan's point it was fitted at
  std::size_t fits = 0;                 // scan points with a smooth neighbourhood
  double deviations = 0;                // the lift, in the fits' own standard deviations
};

// Nothing on a scan whose noise stays under the 5 µm a smooth face may leave (three deviations
// under it). `noise`: the scan's (geometry/cloud_noise.hpp).
NoiseFloor noise_floor(std::span<const Eigen::Vector3d> points, const ScanSurvey& survey, double noise);

}  // namespace drom::geometry
