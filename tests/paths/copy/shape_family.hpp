#pragma once
// A family of scanned shapes whose truth is known (issue 45): analytic solids standing on the stock's
// base (z = 0), their scans (noisy samples of what a scanner sees, a few stray points) and their true
// surfaces sampled densely, hidden faces included (the sides below an open sheet's rim, a hole's wall,
// the base). The parameters are drawn at random from a seed, so the planner is judged on shapes it was
// not tuned to. Kinds:
//   cap        elliptic paraboloid z = H (1 - (x/a)^2 - (y/b)^2), its rim on the base;
//   dome       a spherical cap, its centre below the base (slopes up to 60-80 degrees at the rim);
//   saddle     z = z0 + (x^2/A - y^2/B) over a rectangle, an open sheet standing above the base;
//   step       two tilted plateaus joined by a vertical wall, over a rectangle (the wall scanned);
//   undercut   a ball on a narrower neck (the femur head's shape, random radii);
//   hole       a gently curved plate pierced by a round through hole (its wall not scanned);
//   ridge      a roof with a sharp crest, over a rectangle.
// Nothing here is shared with drom's planner: the test's own geometry, written for the checker.
#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numbers>
#include <random>
#include <string>
#include <vector>

namespace drom::tests::family {

enum class Kind { cap, dome, saddle, step, undercut, hole, ridge };

inline const char* kind_name(Kind k) {
  switch (k) {
    case Kind::cap: return "cap";
    case Kind::dome: return "dome";
    case Kind::saddle: return "saddle";
    case Kind::step: return "step";
    case Kind::undercut: return "undercut";
    case Kind::hole: return "hole";
    case Kind::ridge: return "ridge";
  }
  return "?";
}

struct Samples {
  std::vector<Eigen::Vector3d> points, normals;  // normals outward (out of the solid)
  void add(const Eigen::Vector3d& p, const Eigen::Vector3d& n) { points.push_back(p), normals.push_back(n.normalized()); }
};

struct Shape {
  Kind kind = Kind::cap;
  int index = 0;
  std::string name;                  // kind, index and every drawn parameter
  double spacing = 0.5, noise = 0;   // of the scan, mm
  bool grid = true;                  // the scan on a jittered grid (a laser line scanner) or at random
  bool convex_height_field = false;  // every point seen from +Z: a 3-axis part
  bool undercut = false;             // some point no direction within 90 degrees of +Z reaches
  Samples scan;                      // what the scanner returned, noise included, outliers last
  std::size_t outliers = 0;          // stray points at the end of scan.points
  Samples scanned_truth;             // the scanned faces, noise-free, dense (the surface to copy)
  Samples hidden_truth;              // faces the scan does not show: sides below the rim, the hole's wall
  std::vector<Eigen::Vector3d> open_edge;  // where the scanned faces end and the hidden ones begin (the true rim)
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();  // the solid's box
};

namespace detail {

// A height field z = f(x, y) over a domain, with its gradient.
struct HeightField {
  std::function<double(double, double)> f;
  std::function<Eigen::Vector2d(double, double)> grad;
  std::function<bool(double, double)> inside;
  double x0, x1, y0, y1;
  Eigen::Vector3d normal(double x, double y) const {
    const Eigen::Vector2d g = grad(x, y);
    return Eigen::Vector3d(-g.x(), -g.y(), 1).normalized();
  }
};

// Samples over a height field: a grid of `spacing` in XY jittered by 15 % (a laser line scanner seen
// from above: slopes get sparser on the surface), or uniform at random at one point per spacing^2 of
// surface.
inline void sample_field(const HeightField& h, double spacing, bool grid, double noise, std::mt19937& rng, Samples& scan, Samples* truth) {
  std::uniform_real_distribution<double> u(0, 1);
  std::normal_distribution<double> gauss(0, 1);
  if (grid) {
    const int nx = std::max(1, static_cast<int>(std::ceil((h.x1 - h.x0) / spacing))), ny = std::max(1, static_cast<int>(std::ceil((h.y1 - h.y0) / spacing)));
    for (int j = 0; j <= ny; ++j)
      for (int i = 0; i <= nx; ++i) {
        const double x = h.x0 + (h.x1 - h.x0) * i / nx + (i > 0 && i < nx ? (u(rng) - 0.5) * 0.3 * spacing : 0.0);
        const double y = h.y0 + (h.y1 - h.y0) * j / ny + (j > 0 && j < ny ? (u(rng) - 0.5) * 0.3 * spacing : 0.0);
        if (!h.inside(x, y)) continue;
        const Eigen::Vector3d n = h.normal(x, y), p(x, y, h.f(x, y));
        scan.add(p + (noise > 0 ? noise * gauss(rng) : 0.0) * n, n);
        if (truth) truth->add(p, n);
      }
    return;
  }
  // Projected spacing shrinks by sqrt(n_z) so the surface density is about 1/spacing^2 on slopes up to
  // 80 degrees; candidates are drawn at the densest rate and thinned.
  const double dense = spacing * std::sqrt(std::cos(80 * std::numbers::pi / 180));
  const int nx = std::max(1, static_cast<int>(std::ceil((h.x1 - h.x0) / dense))), ny = std::max(1, static_cast<int>(std::ceil((h.y1 - h.y0) / dense)));
  const double keep_scale = dense * dense / (spacing * spacing);
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      (void)i, (void)j;
      const double x = h.x0 + u(rng) * (h.x1 - h.x0), y = h.y0 + u(rng) * (h.y1 - h.y0);
      if (!h.inside(x, y)) continue;
      const Eigen::Vector3d n = h.normal(x, y);
      // Keep with probability (projected area per candidate) / (projected area per surface sample).
      if (u(rng) > keep_scale / std::max(n.z(), 1e-3)) continue;
      const Eigen::Vector3d p(x, y, h.f(x, y));
      scan.add(p + (noise > 0 ? noise * gauss(rng) : 0.0) * n, n);
      if (truth) truth->add(p, n);
    }
}

// The true surface of a height field on a fine grid (every node inside the domain).
inline void truth_field(const HeightField& h, double step, Samples& truth) {
  const int nx = static_cast<int>(std::ceil((h.x1 - h.x0) / step)), ny = static_cast<int>(std::ceil((h.y1 - h.y0) / step));
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const double x = h.x0 + (h.x1 - h.x0) * i / nx, y = h.y0 + (h.y1 - h.y0) * j / ny;
      if (h.inside(x, y)) truth.add({x, y, h.f(x, y)}, h.normal(x, y));
    }
}

// A vertical face below a curve of the rim, from the rim down to z = 0: (x(t), y(t)) for t in [0, 1],
// outward normal `out(t)` (horizontal).
inline void vertical_face(const std::function<Eigen::Vector2d(double)>& curve, const std::function<Eigen::Vector2d(double)>& out, double length,
                          const std::function<double(double, double)>& top, double step, Samples& truth, std::vector<Eigen::Vector3d>& edge) {
  const int n = std::max(2, static_cast<int>(std::ceil(length / step)));
  for (int k = 0; k <= n; ++k) {
    const double t = static_cast<double>(k) / n;
    const Eigen::Vector2d c = curve(t), o = out(t);
    const double z1 = top(c.x(), c.y());
    const int m = std::max(1, static_cast<int>(std::ceil(z1 / step)));
    for (int l = 0; l < m; ++l) truth.add({c.x(), c.y(), z1 * l / m}, {o.x(), o.y(), 0});
    edge.emplace_back(c.x(), c.y(), z1);
  }
}

// The four vertical sides of a rectangle [x0, x1] x [y0, y1] below the field.
inline void rectangle_sides(const HeightField& h, double step, Samples& truth, std::vector<Eigen::Vector3d>& edge) {
  const double x0 = h.x0, x1 = h.x1, y0 = h.y0, y1 = h.y1;
  vertical_face([&](double t) { return Eigen::Vector2d(x0 + t * (x1 - x0), y0); }, [](double) { return Eigen::Vector2d(0, -1); }, x1 - x0, h.f, step, truth, edge);
  vertical_face([&](double t) { return Eigen::Vector2d(x0 + t * (x1 - x0), y1); }, [](double) { return Eigen::Vector2d(0, 1); }, x1 - x0, h.f, step, truth, edge);
  vertical_face([&](double t) { return Eigen::Vector2d(x0, y0 + t * (y1 - y0)); }, [](double) { return Eigen::Vector2d(-1, 0); }, y1 - y0, h.f, step, truth, edge);
  vertical_face([&](double t) { return Eigen::Vector2d(x1, y0 + t * (y1 - y0)); }, [](double) { return Eigen::Vector2d(1, 0); }, y1 - y0, h.f, step, truth, edge);
}

inline Eigen::Vector3d box_lo(const Samples& s) {
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(1e300);
  for (const auto& p : s.points) lo = lo.cwiseMin(p);
  return lo;
}
inline Eigen::Vector3d box_hi(const Samples& s) {
  Eigen::Vector3d hi = Eigen::Vector3d::Constant(-1e300);
  for (const auto& p : s.points) hi = hi.cwiseMax(p);
  return hi;
}

}  // namespace detail

// Stray points: a reflection, the fixture at the edge of the field of view. Each at least 8 mm and 30
// spacings away from the solid's box (beyond what geometry/cloud_outliers.hpp promises to find: ten
// times the median distance to the 8th neighbour, about 16 spacings), and 30 mm farther at most.
inline void add_outliers(Shape& s, int count, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  const double gap = std::max(8.0, 30 * s.spacing);
  for (int k = 0; k < count; ++k) {
    Eigen::Vector3d p;
    const int face = static_cast<int>(u(rng) * 5);  // above, or beside on one of four sides
    p = s.lo + (s.hi - s.lo).cwiseProduct(Eigen::Vector3d(u(rng), u(rng), u(rng)));
    const double away = gap + u(rng) * 30;
    if (face == 0) p.z() = s.hi.z() + away;
    else if (face == 1) p.x() = s.lo.x() - away;
    else if (face == 2) p.x() = s.hi.x() + away;
    else if (face == 3) p.y() = s.lo.y() - away;
    else p.y() = s.hi.y() + away;
    s.scan.add(p, Eigen::Vector3d::UnitZ());
    ++s.outliers;
  }
}

// One shape of `kind`, its parameters drawn from `seed`. `max_points` caps the scan's size (the
// spacing drawn in [0.1, 1] mm is coarsened until the shape fits).
inline Shape make_shape(Kind kind, int index, unsigned seed, std::size_t max_points = 60000) {
  using detail::HeightField;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  const auto between = [&](double a, double b) { return a + (b - a) * u(rng); };
  Shape s;
  s.kind = kind, s.index = index;
  s.noise = u(rng) < 0.25 ? 0.0 : between(0.005, 0.1);
  s.grid = u(rng) < 0.6;
  double spacing = std::exp(between(std::log(0.1), std::log(1.0)));
  const double truth_step = 0.12;
  char text[256];
  // Area for the spacing cap: the box's footprint (a fair over-estimate of each kind's surface).
  const auto fit_spacing = [&](double area) { spacing = std::max(spacing, std::sqrt(area / static_cast<double>(max_points))); };
  switch (kind) {
    case Kind::cap: {
      const double a = between(12, 40), b = between(10, 30), H = between(3, 25);
      fit_spacing(std::numbers::pi * a * b * (1 + H / std::min(a, b)));
      HeightField h{[=](double x, double y) { return H * (1 - x * x / (a * a) - y * y / (b * b)); },
                    [=](double x, double y) { return Eigen::Vector2d(-2 * H * x / (a * a), -2 * H * y / (b * b)); },
                    [=](double x, double y) { return x * x / (a * a) + y * y / (b * b) <= 1; }, -a, a, -b, b};
      detail::sample_field(h, spacing, s.grid, s.noise, rng, s.scan, nullptr);
      detail::truth_field(h, truth_step, s.scanned_truth);
      s.convex_height_field = true;
      std::snprintf(text, sizeof text, "cap %d: %.1f x %.1f x %.1f mm", index, 2 * a, 2 * b, H);
      break;
    }
    case Kind::dome: {
      const double R = between(8, 30), rim_slope = between(55, 80) * std::numbers::pi / 180, d = R * std::cos(rim_slope);
      const double r = R * std::sin(rim_slope);
      fit_spacing(2 * std::numbers::pi * R * (R - d));
      HeightField h{[=](double x, double y) { return std::sqrt(std::max(0.0, R * R - x * x - y * y)) - d; },
                    [=](double x, double y) {
                      const double z = std::sqrt(std::max(1e-12, R * R - x * x - y * y));
                      return Eigen::Vector2d(-x / z, -y / z);
                    },
                    [=](double x, double y) { return x * x + y * y <= r * r; }, -r, r, -r, r};
      detail::sample_field(h, spacing, s.grid, s.noise, rng, s.scan, nullptr);
      detail::truth_field(h, truth_step, s.scanned_truth);
      s.convex_height_field = true;
      std::snprintf(text, sizeof text, "dome %d: sphere R %.1f, %.1f mm high, rim slope %.0f deg", index, R, R - d, rim_slope * 180 / std::numbers::pi);
      break;
    }
    case Kind::saddle: {
      const double a = between(12, 35), b = between(10, 30), A = between(40, 200), B = between(40, 200) * (u(rng) < 0.5 ? 1 : -1);
      const double z0 = between(3, 12) + b * b / std::max(B, 1.0) * (B > 0);
      fit_spacing(4 * a * b * 1.3);
      HeightField h{[=](double x, double y) { return z0 + x * x / A - y * y / B; },
                    [=](double x, double y) { return Eigen::Vector2d(2 * x / A, -2 * y / B); },
                    [](double, double) { return true; }, -a, a, -b, b};
      detail::sample_field(h, spacing, s.grid, s.noise, rng, s.scan, nullptr);
      detail::truth_field(h, truth_step, s.scanned_truth);
      detail::rectangle_sides(h, truth_step, s.hidden_truth, s.open_edge);
      std::snprintf(text, sizeof text, "saddle %d: %.1f x %.1f mm, z0 %.1f, A %.0f, B %.0f", index, 2 * a, 2 * b, z0, A, B);
      break;
    }
    case Kind::step: {
      const double a = between(12, 35), b = between(10, 25), low = between(2, 8), rise = between(3, 12), xw = between(-0.4, 0.4) * a;
      const double gx = between(-0.15, 0.15), gy = between(-0.25, 0.25);
      fit_spacing(4 * a * b * 1.2 + 2 * b * rise);
      // Lifted so that its lowest corner stands at `low` above the base.
      const double lift = low - std::min(gx * (-a - xw), gx * (a - xw)) + std::abs(gy) * b;
      const auto f = [=](double x, double y) { return lift + (x >= xw ? rise : 0.0) + gx * (x - xw) + gy * y; };
      HeightField h{f, [=](double, double) { return Eigen::Vector2d(gx, gy); }, [](double, double) { return true; }, -a, a, -b, b};
      // The two plateaus, and the wall between them (scanned: a scanner tilted towards it sees it).
      detail::sample_field(h, spacing, s.grid, s.noise, rng, s.scan, nullptr);
      detail::truth_field(h, truth_step, s.scanned_truth);
      std::normal_distribution<double> gauss(0, 1);
      const auto wall = [&](double step, bool noisy, Samples& into) {
        const int n = static_cast<int>(std::ceil(2 * b / step));
        for (int k = 0; k <= n; ++k) {
          const double y_grid = -b + 2 * b * k / n;
          const int m = std::max(1, static_cast<int>(std::ceil(rise / step)));
          for (int l = 1; l < m; ++l) {
            const double y = noisy && !s.grid ? -b + 2 * b * u(rng) : y_grid, z0 = f(xw - 1e-9, y), z1 = f(xw, y);
            Eigen::Vector3d p(xw, y, z0 + (z1 - z0) * l / m);
            if (noisy && s.noise > 0) p.x() -= s.noise * gauss(rng);
            into.add(p, -Eigen::Vector3d::UnitX());
          }
        }
      };
      wall(spacing, true, s.scan);
      wall(truth_step, false, s.scanned_truth);
      detail::rectangle_sides(h, truth_step, s.hidden_truth, s.open_edge);
      std::snprintf(text, sizeof text, "step %d: %.1f x %.1f mm, wall %.1f mm at x = %.1f, tilt (%.2f, %.2f)", index, 2 * a, 2 * b, rise, xw, gx, gy);
      break;
    }
    case Kind::undercut: {
      const double head = between(8, 20), neck = head * between(0.35, 0.7), height = head + between(4, 15);
      fit_spacing(4 * std::numbers::pi * head * head + 2 * std::numbers::pi * neck * height);
      std::normal_distribution<double> gauss(0, 1);
      const Eigen::Vector3d centre(0, 0, height);
      const double polar_max = std::numbers::pi - std::asin(neck / head);
      const double neck_top = height - std::sqrt(head * head - neck * neck);
      // The ball (less the cap inside the neck) and the neck, sampled at `step`; noisy for the scan.
      const auto sample = [&](double step, bool noisy, Samples& into) {
        const int rings = static_cast<int>(std::ceil(head * polar_max / step));
        for (int i = 0; i <= rings; ++i) {
          const double polar = polar_max * i / rings, r = head * std::sin(polar);
          const int around = std::max(1, static_cast<int>(std::ceil(2 * std::numbers::pi * r / step)));
          for (int k = 0; k < around; ++k) {
            double phi = 2 * std::numbers::pi * (k + 0.5 * (i % 2)) / around, pol = polar;
            if (noisy && !s.grid) phi = 2 * std::numbers::pi * u(rng), pol = std::acos(std::cos(0.0) - u(rng) * (1 - std::cos(polar_max)));
            const Eigen::Vector3d n(std::sin(pol) * std::cos(phi), std::sin(pol) * std::sin(phi), std::cos(pol));
            into.add(centre + (head + (noisy && s.noise > 0 ? s.noise * gauss(rng) : 0.0)) * n, n);
          }
        }
        const int around = static_cast<int>(std::ceil(2 * std::numbers::pi * neck / step)), levels = static_cast<int>(std::ceil(neck_top / step));
        for (int i = 0; i < levels; ++i)
          for (int k = 0; k < around; ++k) {
            const double phi = 2 * std::numbers::pi * (k + 0.5 * (i % 2)) / around, z = neck_top * (i + 0.5) / levels;
            const Eigen::Vector3d n(std::cos(phi), std::sin(phi), 0);
            into.add(Eigen::Vector3d(0, 0, z) + (neck + (noisy && s.noise > 0 ? s.noise * gauss(rng) : 0.0)) * n, n);
          }
      };
      sample(spacing, true, s.scan);
      sample(truth_step, false, s.scanned_truth);
      s.undercut = true;
      std::snprintf(text, sizeof text, "undercut %d: ball R %.1f at %.1f mm on a neck R %.1f", index, head, height, neck);
      break;
    }
    case Kind::hole: {
      const double a = between(15, 35), b = between(12, 30), t = between(4, 10), c = between(-0.004, 0.004), hole = between(2, 7);
      const double hx = between(-0.5, 0.5) * (a - hole - 3), hy = between(-0.5, 0.5) * (b - hole - 3);
      fit_spacing(4 * a * b);
      HeightField h{[=](double x, double y) { return t + c * (x * x + y * y); }, [=](double x, double y) { return Eigen::Vector2d(2 * c * x, 2 * c * y); },
                    [=](double x, double y) { return std::hypot(x - hx, y - hy) > hole; }, -a, a, -b, b};
      detail::sample_field(h, spacing, s.grid, s.noise, rng, s.scan, nullptr);
      detail::truth_field(h, truth_step, s.scanned_truth);
      detail::rectangle_sides(h, truth_step, s.hidden_truth, s.open_edge);
      detail::vertical_face([=](double q) { return Eigen::Vector2d(hx + hole * std::cos(2 * std::numbers::pi * q), hy + hole * std::sin(2 * std::numbers::pi * q)); },
                            [=](double q) { return Eigen::Vector2d(-std::cos(2 * std::numbers::pi * q), -std::sin(2 * std::numbers::pi * q)); }, 2 * std::numbers::pi * hole,
                            h.f, truth_step, s.hidden_truth, s.open_edge);
      std::snprintf(text, sizeof text, "hole %d: plate %.1f x %.1f x %.1f mm, hole R %.1f at (%.1f, %.1f)", index, 2 * a, 2 * b, t, hole, hx, hy);
      break;
    }
    case Kind::ridge: {
      const double a = between(12, 35), b = between(10, 30), top = between(6, 20), m = between(0.2, 1.2), x0 = between(-0.3, 0.3) * a, gy = between(-0.2, 0.2);
      const double base = top - m * (a + std::abs(x0)) - std::abs(gy) * b;
      const double lift = base < 2 ? 2 - base : 0.0;
      fit_spacing(4 * a * b * std::sqrt(1 + m * m));
      HeightField h{[=](double x, double y) { return lift + top - m * std::abs(x - x0) + gy * y; },
                    [=](double x, double) { return Eigen::Vector2d(x > x0 ? -m : m, gy); }, [](double, double) { return true; }, -a, a, -b, b};
      detail::sample_field(h, spacing, s.grid, s.noise, rng, s.scan, nullptr);
      detail::truth_field(h, truth_step, s.scanned_truth);
      // The crest itself: a noise-free line of truth on it (the grid may miss it).
      for (int k = 0; k <= static_cast<int>(2 * b / truth_step); ++k) {
        const double y = -b + truth_step * k;
        s.scanned_truth.add({x0, y, h.f(x0, y)}, Eigen::Vector3d(0, -gy, 1));
      }
      detail::rectangle_sides(h, truth_step, s.hidden_truth, s.open_edge);
      std::snprintf(text, sizeof text, "ridge %d: %.1f x %.1f mm, crest %.1f mm high at x = %.1f, flanks %.0f deg", index, 2 * a, 2 * b, top + lift, x0,
                    std::atan(m) * 180 / std::numbers::pi);
      break;
    }
  }
  s.spacing = spacing;
  s.lo = detail::box_lo(s.scanned_truth).cwiseMin(s.hidden_truth.points.empty() ? Eigen::Vector3d::Constant(1e300) : detail::box_lo(s.hidden_truth));
  s.hi = detail::box_hi(s.scanned_truth).cwiseMax(s.hidden_truth.points.empty() ? Eigen::Vector3d::Constant(-1e300) : detail::box_hi(s.hidden_truth));
  s.lo.z() = std::min(s.lo.z(), 0.0);
  const int stray = static_cast<int>(u(rng) * 4);  // 0 to 3
  add_outliers(s, stray, rng);
  char tail[160];
  std::snprintf(tail, sizeof tail, "; scan %zu points (%s, spacing %.2f mm, noise %.3f mm, %zu stray)", s.scan.points.size() - s.outliers, s.grid ? "grid" : "random",
                s.spacing, s.noise, s.outliers);
  s.name = std::string(text) + tail;
  return s;
}

// The family: `per_kind` shapes of every kind, from one seed.
inline std::vector<Shape> make_family(int per_kind, unsigned seed = 4545, std::size_t max_points = 60000) {
  std::vector<Shape> out;
  for (int k = 0; k < 7; ++k)
    for (int i = 0; i < per_kind; ++i) out.push_back(make_shape(static_cast<Kind>(k), i, seed + 1000u * static_cast<unsigned>(k) + static_cast<unsigned>(i), max_points));
  return out;
}

}  // namespace drom::tests::family
