#include "geometry/nurbs_surface.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <stdexcept>
#include <string>

namespace drom::geometry {

namespace {

constexpr int kOrder = NurbsSurface::kMaxDegree + 1;

void check_knots(const std::vector<double>& knots, int degree, int count, const char* direction) {
  const std::string d(direction);
  if (degree < 1 || degree > NurbsSurface::kMaxDegree)
    throw std::invalid_argument("degree in " + d + " must be in [1, " + std::to_string(NurbsSurface::kMaxDegree) + "], got " + std::to_string(degree));
  if (count < degree + 1)
    throw std::invalid_argument(std::to_string(count) + " control points in " + d + " are too few for degree " + std::to_string(degree) + " (need at least " +
                                std::to_string(degree + 1) + ")");
  if (static_cast<int>(knots.size()) != count + degree + 1)
    throw std::invalid_argument("the " + d + " knot vector has " + std::to_string(knots.size()) + " knots; " + std::to_string(count) + " control points of degree " +
                                std::to_string(degree) + " need " + std::to_string(count + degree + 1));
  for (std::size_t i = 0; i < knots.size(); ++i) {
    if (!std::isfinite(knots[i])) throw std::invalid_argument("knot " + std::to_string(i + 1) + " in " + d + " is not finite");
    if (i > 0 && knots[i] < knots[i - 1]) throw std::invalid_argument("the " + d + " knots decrease at knot " + std::to_string(i + 1));
  }
  if (!(knots[static_cast<std::size_t>(count)] > knots[static_cast<std::size_t>(degree)]))
    throw std::invalid_argument("the " + d + " knot vector leaves an empty domain");
  // Interior multiplicity above the degree would make the surface discontinuous.
  for (std::size_t i = static_cast<std::size_t>(degree) + 1; i < static_cast<std::size_t>(count); ++i) {
    int m = 1;
    while (i + static_cast<std::size_t>(m) < static_cast<std::size_t>(count) && knots[i + static_cast<std::size_t>(m)] == knots[i]) ++m;
    if (m > degree) throw std::invalid_argument("an interior " + d + " knot repeats more than the degree (the surface would be discontinuous)");
  }
}

// The knot span holding t: knots[span] <= t < knots[span + 1], clamped to the domain's last non-empty span.
int find_span(const std::vector<double>& knots, int degree, int count, double t) {
  if (t >= knots[static_cast<std::size_t>(count)]) {
    int span = count - 1;
    while (span > degree && knots[static_cast<std::size_t>(span)] == knots[static_cast<std::size_t>(span) + 1]) --span;
    return span;
  }
  if (t <= knots[static_cast<std::size_t>(degree)]) {
    int span = degree;
    while (span < count - 1 && knots[static_cast<std::size_t>(span) + 1] == knots[static_cast<std::size_t>(degree)]) ++span;
    return span;
  }
  const auto first = knots.begin() + degree, last = knots.begin() + count + 1;
  return static_cast<int>(std::upper_bound(first, last, t) - knots.begin()) - 1;
}

// Non-zero basis functions at t and their first `order` derivatives (The NURBS Book, A2.3).
// ders[k * kOrder + j]: k-th derivative of N_{span - degree + j}.
void basis_derivatives(const std::vector<double>& knots, int span, int degree, double t, int order, double* ders) {
  std::array<double, kOrder * kOrder> ndu;
  std::array<double, kOrder> left, right;
  std::array<double, 2 * kOrder> a;
  const auto K = [&](int i) { return knots[static_cast<std::size_t>(i)]; };
  const auto NDU = [&](int i, int j) -> double& { return ndu[static_cast<std::size_t>(i * kOrder + j)]; };
  const auto A = [&](int i, int j) -> double& { return a[static_cast<std::size_t>(i * kOrder + j)]; };
  NDU(0, 0) = 1.0;
  for (int j = 1; j <= degree; ++j) {
    left[static_cast<std::size_t>(j)] = t - K(span + 1 - j);
    right[static_cast<std::size_t>(j)] = K(span + j) - t;
    double saved = 0.0;
    for (int r = 0; r < j; ++r) {
      NDU(j, r) = right[static_cast<std::size_t>(r + 1)] + left[static_cast<std::size_t>(j - r)];
      const double temp = NDU(r, j - 1) / NDU(j, r);
      NDU(r, j) = saved + right[static_cast<std::size_t>(r + 1)] * temp;
      saved = left[static_cast<std::size_t>(j - r)] * temp;
    }
    NDU(j, j) = saved;
  }
  for (int j = 0; j <= degree; ++j) ders[j] = NDU(j, degree);
  const int n = std::min(order, degree);
  for (int k = n + 1; k <= order; ++k)
    for (int j = 0; j <= degree; ++j) ders[k * kOrder + j] = 0.0;
  for (int r = 0; r <= degree; ++r) {
    int s1 = 0, s2 = 1;
    A(0, 0) = 1.0;
    for (int k = 1; k <= n; ++k) {
      double d = 0.0;
      const int rk = r - k, pk = degree - k;
      if (r >= k) {
        A(s2, 0) = A(s1, 0) / NDU(pk + 1, rk);
        d = A(s2, 0) * NDU(rk, pk);
      }
      const int j1 = rk >= -1 ? 1 : -rk;
      const int j2 = r - 1 <= pk ? k - 1 : degree - r;
      for (int j = j1; j <= j2; ++j) {
        A(s2, j) = (A(s1, j) - A(s1, j - 1)) / NDU(pk + 1, rk + j);
        d += A(s2, j) * NDU(rk + j, pk);
      }
      if (r <= pk) {
        A(s2, k) = -A(s1, k - 1) / NDU(pk + 1, r);
        d += A(s2, k) * NDU(r, pk);
      }
      ders[k * kOrder + r] = d;
      std::swap(s1, s2);
    }
  }
  double factor = degree;
  for (int k = 1; k <= n; ++k) {
    for (int j = 0; j <= degree; ++j) ders[k * kOrder + j] *= factor;
    factor *= degree - k;
  }
}

}  // namespace

NurbsSurface::NurbsSurface(int degree_u, int degree_v, std::vector<double> knots_u, std::vector<double> knots_v, int count_u, int count_v,
                           std::vector<Eigen::Vector3d> points, std::vector<double> weights)
    : degree_u_(degree_u),
      degree_v_(degree_v),
      count_u_(count_u),
      count_v_(count_v),
      knots_u_(std::move(knots_u)),
      knots_v_(std::move(knots_v)),
      points_(std::move(points)),
      weights_(std::move(weights)) {
  check_knots(knots_u_, degree_u_, count_u_, "u");
  check_knots(knots_v_, degree_v_, count_v_, "v");
  const std::size_t n = static_cast<std::size_t>(count_u_) * static_cast<std::size_t>(count_v_);
  if (points_.size() != n)
    throw std::invalid_argument(std::to_string(points_.size()) + " control points given; a " + std::to_string(count_u_) + " x " + std::to_string(count_v_) +
                                " net needs " + std::to_string(n));
  for (std::size_t i = 0; i < n; ++i)
    if (!points_[i].allFinite()) throw std::invalid_argument("control point " + std::to_string(i + 1) + " is not finite");
  if (weights_.empty()) weights_.assign(n, 1.0);
  if (weights_.size() != n) throw std::invalid_argument(std::to_string(weights_.size()) + " weights given for " + std::to_string(n) + " control points");
  for (std::size_t i = 0; i < n; ++i) {
    if (!(weights_[i] > 0) || !std::isfinite(weights_[i])) throw std::invalid_argument("weight " + std::to_string(i + 1) + " must be positive and finite");
    if (weights_[i] != 1.0) rational_ = true;
  }
}

NurbsSurface::NurbsSurface()
    : NurbsSurface(1, 1, {0, 0, 1, 1}, {0, 0, 1, 1}, 2, 2, {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(0, 1, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(1, 1, 0)}) {}

NurbsSurface NurbsSurface::bezier(int count_u, int count_v, std::vector<Eigen::Vector3d> points, std::vector<double> weights) {
  if (count_u < 2 || count_v < 2) throw std::invalid_argument("a Bézier patch needs at least 2 x 2 control points");
  std::vector<double> ku(static_cast<std::size_t>(2 * count_u), 0.0), kv(static_cast<std::size_t>(2 * count_v), 0.0);
  std::fill(ku.begin() + count_u, ku.end(), 1.0);
  std::fill(kv.begin() + count_v, kv.end(), 1.0);
  return NurbsSurface(count_u - 1, count_v - 1, std::move(ku), std::move(kv), count_u, count_v, std::move(points), std::move(weights));
}

std::vector<double> NurbsSurface::clamped_uniform_knots(int degree, int count) {
  if (degree < 1 || count < degree + 1) throw std::invalid_argument("clamped knots need count >= degree + 1 >= 2");
  std::vector<double> knots(static_cast<std::size_t>(count + degree + 1), 0.0);
  const int spans = count - degree;
  for (int i = 0; i <= spans; ++i) knots[static_cast<std::size_t>(degree + i)] = static_cast<double>(i) / spans;
  for (int i = count; i < count + degree + 1; ++i) knots[static_cast<std::size_t>(i)] = 1.0;
  return knots;
}

SurfaceDerivatives NurbsSurface::derivatives(double u, double v) const {
  const int su = find_span(knots_u_, degree_u_, count_u_, u);
  const int sv = find_span(knots_v_, degree_v_, count_v_, v);
  std::array<double, 3 * kOrder> nu, nv;
  basis_derivatives(knots_u_, su, degree_u_, u, 2, nu.data());
  basis_derivatives(knots_v_, sv, degree_v_, v, 2, nv.data());
  // Homogeneous sums: a[k][l] = d^(k+l) (w P, w) / du^k dv^l, for k + l <= 2.
  Eigen::Vector4d a[3][3];
  for (auto& row : a)
    for (auto& x : row) x.setZero();
  for (int i = 0; i <= degree_u_; ++i) {
    const int ci = su - degree_u_ + i;
    Eigen::Vector4d row[3] = {Eigen::Vector4d::Zero(), Eigen::Vector4d::Zero(), Eigen::Vector4d::Zero()};
    for (int j = 0; j <= degree_v_; ++j) {
      const std::size_t c = static_cast<std::size_t>(ci) * static_cast<std::size_t>(count_v_) + static_cast<std::size_t>(sv - degree_v_ + j);
      const double w = weights_[c];
      const Eigen::Vector4d pw(points_[c].x() * w, points_[c].y() * w, points_[c].z() * w, w);
      for (int l = 0; l <= 2; ++l) row[l] += nv[static_cast<std::size_t>(l * kOrder + j)] * pw;
    }
    for (int k = 0; k <= 2; ++k)
      for (int l = 0; k + l <= 2; ++l) a[k][l] += nu[static_cast<std::size_t>(k * kOrder + i)] * row[l];
  }
  SurfaceDerivatives d;
  const double w = a[0][0].w();
  const auto A = [&](int k, int l) { return Eigen::Vector3d(a[k][l].head<3>()); };
  const auto W = [&](int k, int l) { return a[k][l].w(); };
  d.point = A(0, 0) / w;
  d.du = (A(1, 0) - W(1, 0) * d.point) / w;
  d.dv = (A(0, 1) - W(0, 1) * d.point) / w;
  d.duu = (A(2, 0) - 2 * W(1, 0) * d.du - W(2, 0) * d.point) / w;
  d.duv = (A(1, 1) - W(1, 0) * d.dv - W(0, 1) * d.du - W(1, 1) * d.point) / w;
  d.dvv = (A(0, 2) - 2 * W(0, 1) * d.dv - W(0, 2) * d.point) / w;
  return d;
}

Eigen::Vector3d NurbsSurface::point(double u, double v) const {
  const int su = find_span(knots_u_, degree_u_, count_u_, u);
  const int sv = find_span(knots_v_, degree_v_, count_v_, v);
  std::array<double, 3 * kOrder> nu, nv;
  basis_derivatives(knots_u_, su, degree_u_, u, 0, nu.data());
  basis_derivatives(knots_v_, sv, degree_v_, v, 0, nv.data());
  Eigen::Vector4d sum = Eigen::Vector4d::Zero();
  for (int i = 0; i <= degree_u_; ++i) {
    Eigen::Vector4d row = Eigen::Vector4d::Zero();
    const std::size_t base = static_cast<std::size_t>(su - degree_u_ + i) * static_cast<std::size_t>(count_v_) + static_cast<std::size_t>(sv - degree_v_);
    for (int j = 0; j <= degree_v_; ++j) {
      const std::size_t c = base + static_cast<std::size_t>(j);
      const double w = weights_[c];
      row += nv[static_cast<std::size_t>(j)] * Eigen::Vector4d(points_[c].x() * w, points_[c].y() * w, points_[c].z() * w, w);
    }
    sum += nu[static_cast<std::size_t>(i)] * row;
  }
  return sum.head<3>() / sum.w();
}

NurbsSurface NurbsSurface::with_unit_domain() const {
  const auto rescale = [](std::vector<double> knots, double lo, double hi) {
    for (double& k : knots) k = (k - lo) / (hi - lo);
    return knots;
  };
  return NurbsSurface(degree_u_, degree_v_, rescale(knots_u_, u_min(), u_max()), rescale(knots_v_, v_min(), v_max()), count_u_, count_v_, points_,
                      rational_ ? weights_ : std::vector<double>{});
}

}  // namespace drom::geometry
