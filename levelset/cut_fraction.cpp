#include "levelset/cut_fraction.hpp"

#include <Eigen/Core>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>

namespace drom::levelset {

namespace {

// Product of the edge ratios at vertex `a`, whose sign differs from the other three: the corner
// tetrahedron the zero plane cuts off at `a`, as a share of the whole.
double corner_share(const std::array<double, 4>& f, int a) {
  double share = 1;
  for (int j = 0; j < 4; ++j)
    if (j != a) share *= f[static_cast<std::size_t>(a)] / (f[static_cast<std::size_t>(a)] - f[static_cast<std::size_t>(j)]);
  return share;
}

double det(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
  return std::abs((b - a).dot((c - a).cross(d - a)));
}

}  // namespace

double negative_fraction(double f0, double f1, double f2, double f3) {
  const std::array<double, 4> f{f0, f1, f2, f3};
  std::array<int, 4> negative{}, other{};
  int nn = 0, no = 0;
  for (int j = 0; j < 4; ++j) {
    if (f[static_cast<std::size_t>(j)] < 0) negative[static_cast<std::size_t>(nn++)] = j;
    else other[static_cast<std::size_t>(no++)] = j;
  }
  switch (nn) {
    case 0: return 0;
    case 4: return 1;
    case 1: return std::clamp(corner_share(f, negative[0]), 0.0, 1.0);
    case 3: return std::clamp(1 - corner_share(f, other[0]), 0.0, 1.0);
    default: break;
  }
  // Two on each side: the negative region is the prism between the edge a-b and the zero plane's
  // quadrilateral. In the reference tetrahedron (volume 1/6) its share is the sum of |det| of the
  // three tetrahedra the prism splits into.
  static const Eigen::Vector3d corner[4] = {Eigen::Vector3d::Zero(), Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), Eigen::Vector3d::UnitZ()};
  const int a = negative[0], b = negative[1], c = other[0], d = other[1];
  auto cut = [&](int i, int j) {
    const double t = f[static_cast<std::size_t>(i)] / (f[static_cast<std::size_t>(i)] - f[static_cast<std::size_t>(j)]);
    return Eigen::Vector3d(corner[i] + t * (corner[j] - corner[i]));
  };
  const Eigen::Vector3d A = corner[a], B = cut(a, c), C = cut(a, d), D = corner[b], E = cut(b, c), F = cut(b, d);
  return std::clamp(det(A, B, C, D) + det(B, C, D, E) + det(C, D, E, F), 0.0, 1.0);
}

}  // namespace drom::levelset
