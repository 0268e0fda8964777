#include "paths/copy/sphere_normals.hpp"

#include "geometry/cloud_bins.hpp"
#include "geometry/point_cloud.hpp"
#include "paths/copy/tool_drop.hpp"

#include <Eigen/Geometry>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <stdexcept>

namespace drom::paths {

double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b) { return std::atan2(a.cross(b).norm(), a.dot(b)); }

PointNormals launch_spheres(std::span<const Eigen::Vector3d> cloud, const SphereLaunchSettings& s, std::span<const Eigen::Vector3d> blockers) {
  if (!(s.diameter > 0) || !(s.grid_step > 0)) throw std::invalid_argument("sphere launching: the diameter and the grid step must be positive");
  if (s.directions.empty()) throw std::invalid_argument("sphere launching: no launch direction");
  const Tool sphere{ToolKind::ball, s.diameter / 2, s.diameter / 2};
  std::vector<Eigen::Vector3d> sum(cloud.size(), Eigen::Vector3d::Zero());
  std::vector<int> hits(cloud.size(), 0);
  PointNormals out;
  for (const auto& direction : s.directions) {
    const Eigen::Matrix3d q = geometry::frame_along(direction);
    std::vector<Eigen::Vector3d> turned = geometry::rotated(cloud, q);
    for (const auto& b : blockers) turned.push_back(q * b);  // indices past the cloud's: no normal
    const geometry::Box3 box = geometry::bounding_box(turned);
    // About 24 points a bin where the scan is dense (a speed knob only: the drop is the same).
    const double density = static_cast<double>(turned.size()) / std::max(1.0, (box.hi.x() - box.lo.x()) * (box.hi.y() - box.lo.y()));
    const geometry::CloudBins bins(turned, std::clamp(std::sqrt(24 / std::max(density, 1e-9)), 0.25, std::max(s.grid_step, sphere.radius / 2)));
    const int nx = static_cast<int>(std::floor((box.hi.x() - box.lo.x()) / s.grid_step)) + 1;
    const int ny = static_cast<int>(std::floor((box.hi.y() - box.lo.y()) / s.grid_step)) + 1;
    out.launches += static_cast<long long>(nx) * ny;
    // Per row of nodes, then merged in order: the sums do not depend on the threads.
    std::vector<std::vector<std::pair<int, Eigen::Vector3d>>> found(static_cast<std::size_t>(ny));
    tbb::parallel_for(0, ny, [&](int j) {
      for (int i = 0; i < nx; ++i) {
        const double x = box.lo.x() + i * s.grid_step, y = box.lo.y() + j * s.grid_step;
        if (s.inside_only && !(bins.max_z_within(x, y, s.grid_step) > -1e300)) continue;
        const Drop d = drop_tool(bins, x, y, sphere);
        if (!d.contact || d.point >= static_cast<int>(cloud.size())) continue;
        found[static_cast<std::size_t>(j)].emplace_back(d.point, q.transpose() * d.normal);
      }
    });
    for (const auto& row : found)
      for (const auto& [point, normal] : row) {
        sum[static_cast<std::size_t>(point)] += normal;
        ++hits[static_cast<std::size_t>(point)];
        ++out.contacts;
      }
  }
  for (std::size_t i = 0; i < cloud.size(); ++i) {
    if (hits[i] == 0) continue;
    const double length = sum[i].norm();
    if (!(length > 1e-12)) continue;  // opposite launches cancelled out: no direction to give
    out.points.push_back(static_cast<int>(i));
    out.normals.push_back(sum[i] / length);
    out.hits.push_back(hits[i]);
  }
  return out;
}

}  // namespace drom::paths
