#pragma once
// Far outliers in a scan: a stray point metres from the part (a reflection, a fly, the fixture
// caught at the edge of the field of view) that would otherwise stretch the stock, the visibility
// sphere and the packets over empty space.
//
// The rule. For every point, d8 = the distance to its 8th nearest neighbour (nanoflann). A point is a
// far outlier when d8 > max(median(d8) + 20 * 1.4826 * MAD(d8), 10 * median(d8)): it stands more than
// twenty robust standard deviations, and at least ten typical point spacings, from any eight other
// points. The median and MAD are robust to the outliers themselves; the floor of ten spacings keeps a
// regular grid (MAD near 0) from losing its edge and corner points (their d8 is at most about twice the
// median). What the rule cannot see: a cluster of nine or more stray points, which is a surface.
// A cloud of 9 points or fewer, or one where most points are stacked on others (median d8 = 0), has
// no spacing to measure against: no point is called an outlier.
#include "geometry/point_cloud.hpp"

#include <cstddef>
#include <vector>

namespace drom::geometry {

struct FarOutlierRule {
  int neighbour = 8;               // d_k with k = neighbour
  double robust_deviations = 20;   // median + this * 1.4826 * MAD
  double spacings = 10;            // and at least this * median
};

struct FarOutliers {
  std::vector<std::size_t> indices;  // increasing
  double threshold_mm = 0;           // the d_k above which a point is an outlier
  double median_mm = 0;              // median d_k (a typical spacing)
};

FarOutliers find_far_outliers(const PointCloud& cloud, const FarOutlierRule& rule = {});

// The cloud without the points at `indices` (increasing); normals follow their points.
void remove_points(PointCloud& cloud, const std::vector<std::size_t>& indices);

}  // namespace drom::geometry
