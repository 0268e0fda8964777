#include "geometry/local_geometry.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace drom::geometry {

LocalGeometry local_geometry(const SurfaceDerivatives& d) {
  LocalGeometry g;
  g.point = d.point;
  const Eigen::Vector3d cross = d.du.cross(d.dv);
  g.area_element = cross.norm();
  const double scale = d.du.squaredNorm() + d.dv.squaredNorm();
  if (!(g.area_element > 1e-14 * scale) || !std::isfinite(g.area_element)) {
    std::ostringstream msg;
    msg << "the surface has no normal at (" << d.point.transpose() << "): S_u x S_v vanishes (a degenerate patch)";
    throw std::domain_error(msg.str());
  }
  g.normal = cross / g.area_element;
  g.E = d.du.dot(d.du);
  g.F = d.du.dot(d.dv);
  g.G = d.dv.dot(d.dv);
  g.L = d.duu.dot(g.normal);
  g.M = d.duv.dot(g.normal);
  g.N = d.dvv.dot(g.normal);
  const double det = g.E * g.G - g.F * g.F;
  g.gaussian = (g.L * g.N - g.M * g.M) / det;
  g.mean = (g.E * g.N - 2 * g.F * g.M + g.G * g.L) / (2 * det);
  // Curvature tensor: with J = [S_u S_v] and P = (J'J)^-1 J', the tangent t has parameters P t and
  // II(P t) is its normal curvature times |t|^2.
  Eigen::Matrix<double, 3, 2> J;
  J << d.du, d.dv;
  Eigen::Matrix2d first, second;
  first << g.E, g.F, g.F, g.G;
  second << g.L, g.M, g.M, g.N;
  const Eigen::Matrix<double, 2, 3> P = first.inverse() * J.transpose();
  g.curvature = P.transpose() * second * P;
  // Principal curvatures and directions: the 2 x 2 tensor in an orthonormal tangent basis.
  const Eigen::Vector3d e1 = d.du.normalized(), e2 = g.normal.cross(e1);
  const double a = e1.dot(g.curvature * e1), b = e1.dot(g.curvature * e2), c = e2.dot(g.curvature * e2);
  const double half_gap = std::sqrt(0.25 * (a - c) * (a - c) + b * b);
  g.kappa1 = 0.5 * (a + c) + half_gap;
  g.kappa2 = 0.5 * (a + c) - half_gap;
  // Eigenvector of [[a, b], [b, c]] for kappa1; at an umbilic any direction will do.
  const double angle = 0.5 * std::atan2(2 * b, a - c);
  g.direction1 = std::cos(angle) * e1 + std::sin(angle) * e2;
  g.direction2 = g.normal.cross(g.direction1);
  return g;
}

double slope(const Eigen::Vector3d& normal, const Eigen::Vector3d& axis) { return std::acos(std::min(1.0, std::abs(normal.dot(axis)))); }

double steepest_azimuth(const Eigen::Vector3d& normal) {
  if (normal.x() == 0 && normal.y() == 0) return 0;
  double a = std::atan2(normal.y(), normal.x());
  constexpr double pi = std::numbers::pi;
  while (a >= pi / 2) a -= pi;
  while (a < -pi / 2) a += pi;
  return a;
}

std::optional<Eigen::Vector2d> find_degenerate_point(const NurbsSurface& surface, int cells_u, int cells_v, double relative_tolerance) {
  Eigen::Vector3d lo = surface.points().front(), hi = lo;
  for (const auto& p : surface.points()) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  const double size = (hi - lo).norm();
  if (!(size > 0)) return Eigen::Vector2d(surface.u_min(), surface.v_min());
  for (int i = 0; i <= cells_u; ++i)
    for (int j = 0; j <= cells_v; ++j) {
      const double u = surface.u_min() + (surface.u_max() - surface.u_min()) * i / cells_u;
      const double v = surface.v_min() + (surface.v_max() - surface.v_min()) * j / cells_v;
      const auto d = surface.derivatives(u, v);
      if (!(d.du.cross(d.dv).norm() > relative_tolerance * size * size)) return Eigen::Vector2d(u, v);
    }
  return std::nullopt;
}

}  // namespace drom::geometry
