#include "geometry/cloud_outliers.hpp"

#include "geometry/cloud_kdtree.hpp"

#include <algorithm>
#include <cmath>

namespace drom::geometry {

namespace {

double median_of(std::vector<double> v) {
  if (v.empty()) return 0;
  const auto mid = v.begin() + static_cast<std::ptrdiff_t>(v.size() / 2);
  std::nth_element(v.begin(), mid, v.end());
  return *mid;
}

}  // namespace

FarOutliers find_far_outliers(const PointCloud& cloud, const FarOutlierRule& rule) {
  FarOutliers out;
  const std::size_t n = cloud.size();
  const int k = rule.neighbour;
  if (n <= static_cast<std::size_t>(k) + 1) return out;  // too few points to tell a stray one from the rest
  const CloudKdTree tree(cloud.points);
  std::vector<double> dk(n);
  std::vector<int> indices;
  std::vector<double> squared;
  for (std::ptrdiff_t i = 0; i < static_cast<std::ptrdiff_t>(n); ++i) {
    tree.nearest(cloud.points[static_cast<std::size_t>(i)], k + 1, indices, squared);  // the point itself comes first
    dk[static_cast<std::size_t>(i)] = std::sqrt(squared.back());
  }
  out.median_mm = median_of(dk);
  // Most points stacked on others (a scan saved twice, a grid written nine times over): there is no
  // spacing to measure distance in, and no point is called an outlier.
  if (!(out.median_mm > 0)) return out;
  std::vector<double> deviation(n);
  for (std::size_t i = 0; i < n; ++i) deviation[i] = std::abs(dk[i] - out.median_mm);
  const double mad = median_of(std::move(deviation));
  out.threshold_mm = std::max(out.median_mm + rule.robust_deviations * 1.4826 * mad, rule.spacings * out.median_mm);
  for (std::size_t i = 0; i < n; ++i)
    if (dk[i] > out.threshold_mm) out.indices.push_back(i);
  return out;
}

void remove_points(PointCloud& cloud, const std::vector<std::size_t>& indices) {
  if (indices.empty()) return;
  std::size_t kept = 0, next = 0;
  for (std::size_t i = 0; i < cloud.points.size(); ++i) {
    if (next < indices.size() && indices[next] == i) {
      ++next;
      continue;
    }
    cloud.points[kept] = cloud.points[i];
    if (cloud.has_normals()) cloud.normals[kept] = cloud.normals[i];
    ++kept;
  }
  cloud.points.resize(kept);
  if (cloud.has_normals()) cloud.normals.resize(kept);
}

}  // namespace drom::geometry
