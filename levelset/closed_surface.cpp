#include "levelset/closed_surface.hpp"

#include "support/input_error.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

namespace drom::levelset {

namespace {

std::vector<std::array<Eigen::Vector3d, 3>> read_stl_triangles(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open STL file");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<std::array<Eigen::Vector3d, 3>> triangles;

  auto binary_size_matches = [&] {
    if (bytes.size() < 84) return false;
    std::uint32_t n = 0;
    std::memcpy(&n, bytes.data() + 80, 4);
    return bytes.size() == 84 + 50ull * n;
  };
  if (binary_size_matches()) {
    std::uint32_t n = 0;
    std::memcpy(&n, bytes.data() + 80, 4);
    for (std::uint32_t t = 0; t < n; ++t) {
      const char* rec = bytes.data() + 84 + 50ull * t + 12;  // skip the normal
      std::array<Eigen::Vector3d, 3> tri;
      for (int v = 0; v < 3; ++v) {
        float xyz[3];
        std::memcpy(xyz, rec + 12 * v, 12);
        tri[static_cast<std::size_t>(v)] = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
        if (!tri[static_cast<std::size_t>(v)].allFinite())
          throw InputError(path.string() + ": facet " + std::to_string(t + 1) + " has a non-finite vertex");
      }
      triangles.push_back(tri);
    }
    return triangles;
  }

  std::istringstream text(bytes);
  std::string line, word;
  int line_no = 0, vertex_in_facet = 0;
  bool seen_solid = false;
  std::array<Eigen::Vector3d, 3> tri;
  while (std::getline(text, line)) {
    ++line_no;
    std::istringstream ls(line);
    if (!(ls >> word)) continue;
    const std::string where = path.string() + ":" + std::to_string(line_no) + ": ";
    if (word == "solid") {
      seen_solid = true;
    } else if (word == "facet") {
      vertex_in_facet = 0;
    } else if (word == "vertex") {
      double x, y, z;
      if (!(ls >> x >> y >> z) || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
        throw InputError(where + "expected 'vertex x y z' with three finite numbers");
      if (vertex_in_facet >= 3) throw InputError(where + "facet has more than three vertices");
      tri[static_cast<std::size_t>(vertex_in_facet++)] = Eigen::Vector3d(x, y, z);
    } else if (word == "endfacet") {
      if (vertex_in_facet != 3) throw InputError(where + "facet has " + std::to_string(vertex_in_facet) + " vertices, expected 3");
      triangles.push_back(tri);
    } else if (word != "outer" && word != "endloop" && word != "endsolid") {
      throw InputError(where + "unexpected '" + word + "' (expected an ASCII STL keyword)");
    }
  }
  if (!seen_solid) throw InputError(path.string() + ": neither a binary STL (size mismatch) nor an ASCII one ('solid' missing)");
  return triangles;
}

}  // namespace

Plc read_closed_stl(const std::filesystem::path& path) {
  const auto triangles = read_stl_triangles(path);
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

}  // namespace drom::levelset
