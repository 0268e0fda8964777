#pragma once
// How noisy a scan is, measured on the scan itself (issue 45): a quadric fitted by least squares to
// the 24 nearest neighbours of a point, in the frame of their least-squares plane, leaves residuals
// that are the scanner's noise (a smooth surface is a quadric at that scale; a plane would also leave
// the curvature). The estimate is the median, over up to 2 000 points drawn with a fixed seed, of each
// fit's residual standard deviation (corrected for the six fitted coefficients). Edges and creases
// fit badly, but they are a minority: the median is the noise of the smooth faces.
#include "geometry/cloud_kdtree.hpp"

#include <Eigen/Core>

#include <span>

namespace drom::geometry {

// The scan's noise standard deviation (mm); 0 for a cloud of fewer than 25 points.
double scan_noise(std::span<const Eigen::Vector3d> points, int samples = 2000);
// With the scan's k-d tree already built.
double scan_noise(std::span<const Eigen::Vector3d> points, const CloudKdTree& tree, int samples = 2000);

}  // namespace drom::geometry
