#include "paths/copy/finishing_floor.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <stdexcept>
#include <unordered_map>

namespace drom::paths {

FinishingFloor finishing_floor(std::span<const Eigen::Vector3d> points, std::span<const Eigen::Vector3d> normals, std::span<const int> members,
                               const Eigen::Matrix3d& frame, double step, double feed, double turn, double cell) {
  if (!(step > 0) || !(feed > 0) || !(cell > 0) || !(turn >= 0)) throw std::invalid_argument("finishing_floor: the step, feed and cell must be positive");
  FinishingFloor out;
  if (members.empty()) return out;
  // The area: the points in cubes of `cell` mm; a plane with unit normal n crosses (|n_x| + |n_y| +
  // |n_z|) / cell^2 cubes per mm^2 of it, so an occupied cube holds cell^2 / (|n_x| + |n_y| + |n_z|)
  // (n the mean of its points' normals): the same whatever the packet's direction.
  struct Cube {
    Eigen::Vector3d normal = Eigen::Vector3d::Zero();
  };
  std::unordered_map<std::uint64_t, Cube> cubes;
  double y_lo = std::numeric_limits<double>::infinity(), y_hi = -y_lo;
  const auto index = [&](double v) { return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(v / cell)) + (std::int64_t{1} << 20)); };
  for (const int m : members) {
    const Eigen::Vector3d& p = points[static_cast<std::size_t>(m)];
    Cube& c = cubes[(index(p.x()) << 42) | (index(p.y()) << 21) | index(p.z())];
    const Eigen::Vector3d& n = normals[static_cast<std::size_t>(m)];
    c.normal += c.normal.dot(n) < 0 ? -n : n;
    const double y = frame.row(1).dot(p);
    y_lo = std::min(y_lo, y), y_hi = std::max(y_hi, y);
  }
  for (const auto& [key, c] : cubes) {
    const Eigen::Vector3d n = c.normal.norm() > 0 ? Eigen::Vector3d(c.normal.normalized()) : Eigen::Vector3d::UnitZ();
    out.area += cell * cell / (std::abs(n.x()) + std::abs(n.y()) + std::abs(n.z()));
  }
  out.length = out.area / step;
  out.passes = std::max(1.0, (y_hi - y_lo + cell) / step);
  out.time = out.length / feed + out.passes * turn;
  return out;
}

}  // namespace drom::paths
