#include "geometry/closed_surface.hpp"

#include "support/input_error.hpp"
#include "support/stl_reader.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

namespace drom::geometry {

Plc read_closed_stl(const std::filesystem::path& path) {
  const auto triangles = read_stl_facets(path);
  if (triangles.size() < 4) throw InputError(path.string() + ": a closed surface needs at least 4 triangles, found " + std::to_string(triangles.size()));

  Eigen::Vector3d lo = triangles[0][0], hi = lo;
  for (const auto& t : triangles)
    for (const auto& v : t) {
      lo = lo.cwiseMin(v);
      hi = hi.cwiseMax(v);
    }
  // Weld vertices closer than a small fraction of the part's size (STL repeats every vertex).
  const double quantum = 1e-9 * std::max(1.0, (hi - lo).norm());
  std::map<std::array<long long, 3>, int> index;
  Plc plc;
  for (std::size_t t = 0; t < triangles.size(); ++t) {
    std::vector<int> facet;
    for (const auto& v : triangles[t]) {
      const std::array<long long, 3> key{std::llround(v.x() / quantum), std::llround(v.y() / quantum), std::llround(v.z() / quantum)};
      auto [it, inserted] = index.try_emplace(key, static_cast<int>(plc.points.size()));
      if (inserted) plc.points.push_back(v);
      facet.push_back(it->second);
    }
    if (facet[0] == facet[1] || facet[1] == facet[2] || facet[0] == facet[2])
      throw InputError(path.string() + ": facet " + std::to_string(t + 1) + " is degenerate (repeated vertex)");
    plc.facets.push_back(facet);
  }

  // Closed and oriented: each directed edge once, and its reverse once.
  std::map<std::pair<int, int>, int> directed;
  for (std::size_t t = 0; t < plc.facets.size(); ++t)
    for (int k = 0; k < 3; ++k) {
      const auto& f = plc.facets[t];
      const std::pair<int, int> e{f[static_cast<std::size_t>(k)], f[static_cast<std::size_t>((k + 1) % 3)]};
      if (!directed.emplace(e, static_cast<int>(t)).second)
        throw InputError(path.string() + ": edge between vertices (" + std::to_string(e.first) + ", " + std::to_string(e.second) +
                         ") is used twice in the same direction (facet " + std::to_string(t + 1) +
                         "): the surface is not consistently oriented or not manifold");
    }
  for (const auto& [e, t] : directed)
    if (!directed.count({e.second, e.first})) {
      const auto& p = plc.points[static_cast<std::size_t>(e.first)];
      std::ostringstream msg;
      msg << path.string() << ": surface is not closed: the edge of facet " << t + 1 << " starting at (" << p.x() << ", " << p.y() << ", "
          << p.z() << ") has no neighbouring facet";
      throw InputError(msg.str());
    }
  return plc;
}

Plc layered_box_plc(const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, std::vector<double> z_levels) {
  std::vector<double> z{lo.z()};
  std::sort(z_levels.begin(), z_levels.end());
  for (double level : z_levels)
    if (level > lo.z() && level < hi.z()) z.push_back(level);
  z.push_back(hi.z());
  Plc plc;
  for (double level : z) {
    plc.points.emplace_back(lo.x(), lo.y(), level);
    plc.points.emplace_back(hi.x(), lo.y(), level);
    plc.points.emplace_back(hi.x(), hi.y(), level);
    plc.points.emplace_back(lo.x(), hi.y(), level);
  }
  for (int k = 0; k < static_cast<int>(z.size()); ++k) plc.facets.push_back({4 * k, 4 * k + 1, 4 * k + 2, 4 * k + 3});
  for (int k = 0; k + 1 < static_cast<int>(z.size()); ++k)
    for (int s = 0; s < 4; ++s) {
      const int a = 4 * k + s, b = 4 * k + (s + 1) % 4;
      plc.facets.push_back({a, b, b + 4, a + 4});
    }
  return plc;
}

}  // namespace drom::geometry
