#pragma once
// Synthetic clouds for the point-cloud tests and benchmark: analytic surfaces sampled (on a grid of
// their XY, or at random), with their exact normals, and the test parts (the seed's
// hemisphere of 2 537 points, a femur-head-like ball on a neck, a mushroom).
#include "geometry/nurbs_surface.hpp"
#include "geometry/local_geometry.hpp"

#include <Eigen/Core>

#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <vector>

namespace drom::tests {

struct SampledSurface {
  std::vector<Eigen::Vector3d> points, normals;  // normals: exact, outward (towards +Z for graphs)
};

// z = f(x, y) sampled on a square grid of `spacing` over [x0, x1] x [y0, y1]; `gradient` gives the
// exact normal. Points where f is NaN are left out.
inline SampledSurface graph_samples(const std::function<double(double, double)>& f, const std::function<Eigen::Vector2d(double, double)>& gradient, double x0,
                                    double x1, double y0, double y1, double spacing) {
  SampledSurface s;
  const int nx = static_cast<int>(std::floor((x1 - x0) / spacing + 1e-9)), ny = static_cast<int>(std::floor((y1 - y0) / spacing + 1e-9));
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const double x = x0 + i * spacing, y = y0 + j * spacing, z = f(x, y);
      if (!std::isfinite(z)) continue;
      const Eigen::Vector2d g = gradient(x, y);
      s.points.emplace_back(x, y, z);
      s.normals.push_back(Eigen::Vector3d(-g.x(), -g.y(), 1).normalized());
    }
  return s;
}

// A sphere's points seen from +Z (z >= centre), uniform at random over the cap up to `max_polar`
// (rad) at `density` points per mm^2, with Gaussian noise of `sigma` mm along Z (a scanner's line of
// sight), exact normals of the noise-free sphere.
inline SampledSurface sphere_cap(const Eigen::Vector3d& centre, double radius, double max_polar, double density, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> noise(0, sigma > 0 ? sigma : 1);
  const double area = 2 * std::numbers::pi * radius * radius * (1 - std::cos(max_polar));
  const auto n = static_cast<long long>(area * density);
  SampledSurface s;
  for (long long k = 0; k < n; ++k) {
    const double z = 1 - u(rng) * (1 - std::cos(max_polar)), phi = 2 * std::numbers::pi * u(rng), r = std::sqrt(std::max(0.0, 1 - z * z));
    const Eigen::Vector3d normal(r * std::cos(phi), r * std::sin(phi), z);
    Eigen::Vector3d p = centre + radius * normal;
    if (sigma > 0) p.z() += noise(rng);
    s.points.push_back(p);
    s.normals.push_back(normal);
  }
  return s;
}

// The seed's synthetic hemisphere (Makki 2009 §3-4.2): 2 537 points, denser towards the top, with
// exact normals C0 Pi: 43 rings of 59 points, polar angles 90/43 ... 90 degrees. Radius 38 mm (the
// seed's printed points lie about 38 mm from its centre).
inline SampledSurface seed_hemisphere(double radius = 38) {
  SampledSurface s;
  for (int ring = 1; ring <= 43; ++ring)
    for (int k = 0; k < 59; ++k) {
      const double polar = std::numbers::pi / 2 * ring / 43, phi = 2 * std::numbers::pi * (k + 0.5 * (ring % 2)) / 59;
      const Eigen::Vector3d n(std::sin(polar) * std::cos(phi), std::sin(polar) * std::sin(phi), std::cos(polar));
      s.points.push_back(radius * n);
      s.normals.push_back(n);
    }
  return s;
}

// A femur-head-like part standing on the table (z = 0): a ball of radius `head` centred at
// (0, 0, height) on a cylindrical neck of radius `neck` along Z from the table up into the ball,
// sampled uniformly at `spacing` mm. The ball's lower half overhangs the neck: an undercut no single
// direction reaches.
inline SampledSurface femur_head(double head = 20, double neck = 9, double height = 45, double spacing = 0.7) {
  SampledSurface s;
  const Eigen::Vector3d centre(0, 0, height);
  // The ball, less the cap inside the neck (polar angle beyond pi - asin(neck / head) from +Z).
  const double polar_max = std::numbers::pi - std::asin(neck / head);
  const int rings = static_cast<int>(std::ceil(head * polar_max / spacing));
  for (int i = 0; i <= rings; ++i) {
    const double polar = polar_max * i / rings, r = head * std::sin(polar);
    const int around = std::max(1, static_cast<int>(std::ceil(2 * std::numbers::pi * r / spacing)));
    for (int k = 0; k < around; ++k) {
      const double phi = 2 * std::numbers::pi * (k + 0.5 * (i % 2)) / around;
      const Eigen::Vector3d n(std::sin(polar) * std::cos(phi), std::sin(polar) * std::sin(phi), std::cos(polar));
      s.points.push_back(centre + head * n);
      s.normals.push_back(n);
    }
  }
  // The neck, from the table to where it enters the ball.
  const double top = height - std::sqrt(head * head - neck * neck);
  const int around = static_cast<int>(std::ceil(2 * std::numbers::pi * neck / spacing));
  const int levels = static_cast<int>(std::ceil(top / spacing));
  for (int i = 0; i < levels; ++i)
    for (int k = 0; k < around; ++k) {
      const double phi = 2 * std::numbers::pi * (k + 0.5 * (i % 2)) / around, z = top * i / levels + 0.5 * top / levels;
      s.points.emplace_back(neck * std::cos(phi), neck * std::sin(phi), z);
      s.normals.emplace_back(std::cos(phi), std::sin(phi), 0);
    }
  return s;
}

// A free-form surface's points at random parameters (uniform in u, v), with noise along the normal
// and the exact normals (towards +Z).
inline SampledSurface surface_samples(const geometry::NurbsSurface& surface, long long count, double sigma, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> noise(0, sigma > 0 ? sigma : 1);
  SampledSurface s;
  for (long long k = 0; k < count; ++k) {
    const auto g = geometry::local_geometry(surface.derivatives(surface.u_min() + u(rng) * (surface.u_max() - surface.u_min()),
                                                                 surface.v_min() + u(rng) * (surface.v_max() - surface.v_min())));
    const Eigen::Vector3d n = geometry::normal_towards(g.normal, Eigen::Vector3d::UnitZ());
    s.points.push_back(sigma > 0 ? Eigen::Vector3d(g.point + noise(rng) * n) : g.point);
    s.normals.push_back(n);
  }
  return s;
}

// A smooth free-form test patch (bicubic Bézier over 80 x 60 mm, a saddle with a bump: slopes to
// about 40 degrees).
inline geometry::NurbsSurface test_patch() {
  std::vector<Eigen::Vector3d> p;
  const double z[4][4] = {{0, 6, 10, 4}, {8, 22, 18, 6}, {4, 16, 26, 12}, {-2, 4, 12, 20}};
  for (int i = 0; i < 4; ++i)
    for (int j = 0; j < 4; ++j) p.emplace_back(80.0 * i / 3, 60.0 * j / 3, z[i][j]);
  return geometry::NurbsSurface::bezier(4, 4, p);
}

}  // namespace drom::tests
