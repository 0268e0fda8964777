#include "paths/orient/repulsive_field.hpp"

#include "geometry/local_geometry.hpp"
#include "geometry/surface_grid.hpp"
#include "support/input_error.hpp"
#include "support/stl_reader.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace drom::paths {

const char* aggregation_name(Aggregation a) {
  switch (a) {
    case Aggregation::F1: return "F1";
    case Aggregation::F2: return "F2";
    case Aggregation::F3: return "F3";
  }
  return "?";
}

Eigen::Vector3d khatib_force(const Eigen::Vector3d& p, const Eigen::Vector3d& o, const KhatibParameters& k) {
  const Eigen::Vector3d d = p - o;
  const double r2 = d.squaredNorm();
  if (r2 >= k.influence_radius * k.influence_radius || r2 == 0) return Eigen::Vector3d::Zero();
  const double r = std::sqrt(r2);
  return (k.eta * (1 / r - 1 / k.influence_radius) / (r2 * r)) * d;
}

double khatib_potential(double r, const KhatibParameters& k) {
  if (r >= k.influence_radius) return 0;
  const double a = 1 / r - 1 / k.influence_radius;
  return 0.5 * k.eta * a * a;
}

void TriangleSoup::append(const TriangleSoup& other) {
  const int base = static_cast<int>(vertices.size());
  vertices.insert(vertices.end(), other.vertices.begin(), other.vertices.end());
  for (const auto& t : other.triangles) triangles.push_back({t[0] + base, t[1] + base, t[2] + base});
}

TriangleSoup triangulate_patch(const geometry::NurbsSurface& surface, double step, bool flip) {
  const auto [cu, cv] = geometry::cells_for_step(surface, step);
  TriangleSoup soup;
  for (int i = 0; i <= cu; ++i)
    for (int j = 0; j <= cv; ++j)
      soup.vertices.push_back(surface.point(surface.u_min() + (surface.u_max() - surface.u_min()) * i / cu,
                                            surface.v_min() + (surface.v_max() - surface.v_min()) * j / cv));
  auto id = [cv = cv](int i, int j) { return i * (cv + 1) + j; };
  for (int i = 0; i < cu; ++i)
    for (int j = 0; j < cv; ++j) {
      // (u, v) counter-clockwise gives the patch normal S_u × S_v.
      std::array<int, 3> a{id(i, j), id(i + 1, j), id(i + 1, j + 1)}, b{id(i, j), id(i + 1, j + 1), id(i, j + 1)};
      if (flip) {
        std::swap(a[1], a[2]);
        std::swap(b[1], b[2]);
      }
      soup.triangles.push_back(a);
      soup.triangles.push_back(b);
    }
  return soup;
}

ObstacleCloud::ObstacleCloud(std::vector<Eigen::Vector3d> points, std::vector<Eigen::Vector3d> normals, double cell)
    : points_(std::move(points)), normals_(std::move(normals)), cell_(cell) {
  rebin();
}

ObstacleCloud ObstacleCloud::from_patch(const geometry::NurbsSurface& surface, double spacing, bool flip_normal, double cell) {
  const auto [cu, cv] = geometry::cells_for_step(surface, spacing);
  const geometry::SurfaceGrid grid = geometry::sample_grid(surface, cu, cv, geometry::GridPlacement::nodes);
  std::vector<Eigen::Vector3d> p, n;
  for (const auto& s : grid.samples) {
    p.push_back(s.point);
    n.push_back(flip_normal ? Eigen::Vector3d(-s.normal) : s.normal);
  }
  return ObstacleCloud(std::move(p), std::move(n), cell);
}

ObstacleCloud ObstacleCloud::from_triangles(const TriangleSoup& soup, double spacing, double cell) {
  std::vector<Eigen::Vector3d> p, n;
  for (const auto& t : soup.triangles) {
    const Eigen::Vector3d a = soup.vertices[t[0]], b = soup.vertices[t[1]], c = soup.vertices[t[2]];
    const Eigen::Vector3d normal = (b - a).cross(c - a);
    if (normal.norm() == 0) continue;
    const double longest = std::max({(b - a).norm(), (c - b).norm(), (a - c).norm()});
    const int m = std::max(1, static_cast<int>(std::ceil(longest / spacing)));
    // Each triangle owns its interior and the edges a→b, b→c (without c→a's end) so shared edges of
    // a strip are sampled about once; a few duplicates on other edges only add F1 weight locally.
    for (int i = 0; i <= m; ++i)
      for (int j = 0; i + j <= m; ++j) {
        if (i == 0 && j > 0 && j < m) continue;  // edge a→c interior: the neighbour's
        const double wb = static_cast<double>(i) / m, wc = static_cast<double>(j) / m;
        p.push_back(a + wb * (b - a) + wc * (c - a));
        n.push_back(normal.normalized());
      }
  }
  return ObstacleCloud(std::move(p), std::move(n), cell);
}

void ObstacleCloud::append(const ObstacleCloud& other) {
  points_.insert(points_.end(), other.points_.begin(), other.points_.end());
  normals_.insert(normals_.end(), other.normals_.begin(), other.normals_.end());
  rebin();
}

void ObstacleCloud::rebin() {
  start_.clear();
  order_.clear();
  if (points_.empty()) return;
  Eigen::Vector3d lo = points_.front(), hi = points_.front();
  for (const auto& p : points_) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  origin_ = lo;
  for (int d = 0; d < 3; ++d) dims_[d] = static_cast<int>(std::floor((hi(d) - lo(d)) / cell_)) + 1;
  const std::size_t cells = static_cast<std::size_t>(dims_[0]) * dims_[1] * dims_[2];
  if (cells > 200'000'000) throw std::invalid_argument("obstacles spread over too many cells of r0: r0 too small for the part");
  std::vector<std::size_t> cell_of(points_.size());
  start_.assign(cells + 1, 0);
  for (std::size_t i = 0; i < points_.size(); ++i) {
    const Eigen::Vector3d q = (points_[i] - origin_) / cell_;
    const auto at = [&](int d) { return std::clamp(static_cast<int>(std::floor(q(d))), 0, dims_[d] - 1); };
    cell_of[i] = (static_cast<std::size_t>(at(0)) * dims_[1] + at(1)) * dims_[2] + at(2);
    ++start_[cell_of[i] + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
  order_.resize(points_.size());
  std::vector<int> fill(start_.begin(), start_.end() - 1);
  for (std::size_t i = 0; i < points_.size(); ++i) order_[fill[cell_of[i]]++] = static_cast<int>(i);
}

int ObstacleCloud::nearest(const Eigen::Vector3d& p, double radius) const {
  int best = -1;
  double best2 = radius * radius;
  for_each_near(p, [&](int i) {
    const double d2 = (points_[i] - p).squaredNorm();
    if (d2 < best2) {
      best2 = d2;
      best = i;
    }
  });
  return best;
}

FieldSample repulsive_force(const ObstacleCloud& obstacles, const Eigen::Vector3d& p, const KhatibParameters& k, Aggregation a) {
  FieldSample s;
  double largest = 0;
  const double r0_2 = k.influence_radius * k.influence_radius;
  obstacles.for_each_near(p, [&](int i) {
    const Eigen::Vector3d d = p - obstacles.points()[i];
    const double r2 = d.squaredNorm();
    if (r2 >= r0_2 || r2 == 0) return;
    const double r = std::sqrt(r2);
    s.nearest = std::min(s.nearest, r);
    const double magnitude = k.eta * (1 / r - 1 / k.influence_radius) / r2;
    s.force += (magnitude / r) * d;
    largest = std::max(largest, magnitude);
    ++s.active;
  });
  if (s.active == 0) return s;
  if (a == Aggregation::F2) s.force /= s.active;
  if (a == Aggregation::F3) {
    const double norm = s.force.norm();
    s.force = norm > 0 ? Eigen::Vector3d(s.force * (largest / norm)) : Eigen::Vector3d::Zero();
  }
  return s;
}

TriangleSoup read_stl_triangles(const std::filesystem::path& path) {
  TriangleSoup soup;
  for (const StlFacet& f : read_stl_facets(path)) {
    const int base = static_cast<int>(soup.vertices.size());
    soup.vertices.insert(soup.vertices.end(), f.begin(), f.end());
    soup.triangles.push_back({base, base + 1, base + 2});
  }
  if (soup.triangles.empty()) throw InputError(path.string() + ": no facet");
  return soup;
}

}  // namespace drom::paths
