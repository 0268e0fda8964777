#include "paths/finish/plane_model.hpp"
#include "paths/cutter/stepover.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>

namespace drom::paths {

namespace {

constexpr double kPi = std::numbers::pi;

// Per pass at the feed (case 2) and per link of length x (case 3).
double pass_overhead(const Kinematics& k) { return 2 * std::sqrt(k.feed / k.jerk); }
double link_time(double x, const Kinematics& k) { return 4 * std::cbrt(x / (2 * k.jerk)); }

double torus_stepover(double slope, double alpha, const Tool& torus, double scallop) {
  return std::min(flat_stepover(scallop, effective_radius(torus, slope, alpha)), level_ground_stepover(torus, scallop));
}

}  // namespace

PlaneTime torus_along_slope(double width, double height, double slope, const Tool& torus, double scallop, const Kinematics& k) {
  PlaneTime t;
  t.stepover = torus_stepover(slope, 0, torus, scallop);
  t.passes = width / t.stepover;
  t.length = t.passes * (height + t.stepover);
  t.time = t.passes * (height / k.feed + pass_overhead(k) + link_time(t.stepover, k));
  return t;
}

PlaneTime ball_along_principal(double width, double height, const Tool& ball, double scallop, const Kinematics& k) {
  PlaneTime t;
  t.stepover = flat_stepover(scallop, ball.radius);
  t.passes = height / t.stepover;
  t.length = t.passes * (width + t.stepover);
  t.time = t.passes * (width / k.feed + pass_overhead(k) + link_time(t.stepover, k));
  return t;
}

double critical_slope(double mu, double chi, const Tool& torus, const Tool& ball, double scallop, const Kinematics& k) {
  const double w = std::sqrt(mu * chi), h = std::sqrt(chi / mu);
  const double T2 = ball_along_principal(w, h, ball, scallop, k).time;
  const double p = 4 * w / (T2 * std::cbrt(2 * k.jerk));
  const double q = w / T2 * (h / k.feed + pass_overhead(k));
  // z^3 - p z - q = 0, z = cbrt(sod1): Cardan where 4p^3 < 27q^2 (one real root), else the largest root.
  const double disc = q * q / 4 - p * p * p / 27;
  double z;
  if (disc >= 0) {
    z = std::cbrt(q / 2 + std::sqrt(disc)) + std::cbrt(q / 2 - std::sqrt(disc));
  } else {
    z = 2 * std::sqrt(p / 3) * std::cos(std::acos(1.5 * q / p * std::sqrt(3 / p)) / 3);
  }
  const double z6 = std::pow(z, 6), sh = scallop, R = torus.radius, r = torus.corner_radius;
  const double s = 8 * sh * (R - r) / (z6 + 4 * sh * sh - 8 * sh * r);
  if (!(s > 0) || s >= 1) return kPi / 2;
  return std::asin(s);
}

double critical_shape_factor(double slope, double chi, const Tool& torus, const Tool& ball, double scallop, const Kinematics& k) {
  const double sod1 = torus_stepover(slope, 0, torus, scallop), sod2 = flat_stepover(scallop, ball.radius);
  const double k1 = pass_overhead(k) + link_time(sod1, k), k2 = pass_overhead(k) + link_time(sod2, k);
  const double a = sod2 / sod1 * k1, b = -std::sqrt(chi) / k.feed * (1 - sod2 / sod1), c = -k2;
  const double root = (-b + std::sqrt(b * b - 4 * a * c)) / (2 * a);
  return std::max(1.0, root * root);
}

ToolVerdict choose_tool(const PcaPlane& plane, const Tool& torus, const Tool& ball, double scallop, const Kinematics& k) {
  ToolVerdict v;
  v.critical_slope = critical_slope(plane.shape_factor, plane.size, torus, ball, scallop, k);
  v.critical_shape = critical_shape_factor(plane.slope, plane.size, torus, ball, scallop, k);
  v.torus = torus_along_slope(plane.width, plane.height, plane.slope, torus, scallop, k);
  v.ball_time = ball_along_principal(plane.width, plane.height, ball, scallop, k);
  v.ball = v.critical_slope < plane.slope;
  v.feed_azimuth = v.ball ? plane.principal_azimuth : plane.steepest_azimuth;
  std::ostringstream s;
  s.precision(3);
  const double deg = 180 / kPi;
  s << "s~ = " << plane.slope * deg << " deg " << (v.ball ? ">" : "<=") << " s_c(mu~ = " << plane.shape_factor << ") = " << v.critical_slope * deg
    << " deg: " << (v.ball ? "ball along the principal direction" : "torus along the steepest slope");
  v.reason = s.str();
  return v;
}

double rectangle_time(double w, double h, double alpha, double p, const Kinematics& k) {
  alpha = std::abs(std::remainder(alpha, kPi));
  if (alpha > kPi / 2) alpha = kPi - alpha;
  const double overhead = pass_overhead(k);
  const double sa = std::sin(alpha), ca = std::cos(alpha);
  // Central passes of constant length l, n of them, spaced delta along the side they start from;
  // two triangular ends of m passes each, the i-th of length i p / (cos a sin a), whose links
  // alternate between the two sides (delta and p / cos a, or p / sin a).
  double l, delta, n, m, side_link;
  if (sa * w >= h * ca) {  // tan(alpha) >= h / w
    l = h / sa;
    delta = p / sa;
    n = sa / p * (w - h * ca / sa);
    m = h * ca / p;
    side_link = ca > 1e-12 ? p / ca : 0;
  } else {
    l = w / ca;
    delta = p / ca;
    n = ca / p * (h - w * sa / ca);
    m = w * sa / p;
    side_link = sa > 1e-12 ? p / sa : 0;
  }
  const double central = n * (l / k.feed + overhead + link_time(delta, k));
  double ends = 0;
  if (m > 0) {
    // The seed sums i = 1..m; with a real-valued m the triangle's area (sum ~ m^2 / 2) keeps the time
    // continuous as alpha -> 0 (the sum's extra m / 2 would add a whole pass there).
    const double first = p / (ca * sa);  // length of the shortest end pass
    ends = first * m * m / 2 / k.feed + m * (overhead + 0.5 * link_time(delta, k) + 0.5 * link_time(side_link, k));
  }
  return central + 2 * ends;
}

double pca_plane_time(const PcaPlane& plane, double theta, const Tool& tool, double scallop, const Kinematics& k) {
  const Eigen::Vector3d x1 = plane.axes.col(0), x3 = plane.axes.col(2);
  Eigen::Vector3d feed(std::cos(theta), std::sin(theta), 0);
  if (std::abs(x3.z()) > 1e-9) feed.z() = -(x3.x() * feed.x() + x3.y() * feed.y()) / x3.z();
  else feed = x3.cross(Eigen::Vector3d::UnitZ()).normalized();  // a vertical plane: feed along its level line
  feed.normalize();
  const double alpha = std::acos(std::min(1.0, std::abs(feed.dot(x1))));
  double to_steepest = kPi / 2;
  if (plane.steepest_direction.norm() > 0) to_steepest = std::acos(std::min(1.0, std::abs(feed.dot(plane.steepest_direction))));
  const double step = std::min(flat_stepover(scallop, effective_radius(tool, plane.slope, to_steepest)), level_ground_stepover(tool, scallop));
  return rectangle_time(plane.width, plane.height, alpha, step, k);
}

}  // namespace drom::paths
