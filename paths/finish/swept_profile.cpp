#include "paths/finish/swept_profile.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <map>
#include <memory>
#include <mutex>
#include <numbers>
#include <tuple>

namespace drom::paths {

double one_pass_reach(const Tool& tool, const Eigen::Vector3d& n, const Eigen::Vector3d& axis, const Eigen::Vector3d& along, const Eigen::Vector3d& across,
                      double curvature, double scallop) {
  const double r = tool.corner_radius, ring = tool.kind == ToolKind::ball ? 0.0 : tool.radius - r;
  // The cross-section frame at the contact: y across, z along the normal; the surface z = kappa y^2 / 2.
  const Eigen::Vector3d y_axis = (across - across.dot(along) * along - across.dot(n) * n).normalized();
  // The tube circle's centre (on the axis), from the contact: the tube's centre r along the normal,
  // then R - r on along the normal's part across the axis (the tool's outer side faces the ground).
  Eigen::Vector3d centre = r * n;
  const Eigen::Vector3d radial = n - n.dot(axis) * axis;
  if (ring > 0 && radial.norm() > 1e-12) centre += ring * radial.normalized();
  Eigen::Vector3d e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
  // The tube circle projected along the pass: the disks' centres, sampled every degree; the lowest
  // disk then refined by golden section between its neighbours (sampling alone is off by up to
  // (R - r)(1 - cos 0.5 deg), 0.1 um, on the safe side).
  const auto disk = [&](double phi) {
    const Eigen::Vector3d c = centre + ring * (std::cos(phi) * e1 + std::sin(phi) * e2);
    return Eigen::Vector2d(y_axis.dot(c), n.dot(c));
  };
  constexpr int kRing = 360;
  std::array<Eigen::Vector2d, kRing> disks;
  const int count = ring > 0 ? kRing : 1;
  const double dphi = 2 * std::numbers::pi / kRing;
  for (int k = 0; k < count; ++k) disks[static_cast<std::size_t>(k)] = disk(k * dphi);
  const auto below = [&](const Eigen::Vector2d& d, double y) {
    const double dy = y - d.x();
    return std::abs(dy) < r ? d.y() - std::sqrt(r * r - dy * dy) : std::numeric_limits<double>::infinity();
  };
  const auto gap = [&](double y) {
    double lowest = std::numeric_limits<double>::infinity();
    int best = -1;
    for (int k = 0; k < count; ++k) {
      const double z = below(disks[static_cast<std::size_t>(k)], y);
      if (z < lowest) {
        lowest = z;
        best = k;
      }
    }
    if (best >= 0 && ring > 0) {
      double a = (best - 1) * dphi, b = (best + 1) * dphi;
      constexpr double g = 0.6180339887498949;
      for (int it = 0; it < 30; ++it) {
        const double x1 = b - g * (b - a), x2 = a + g * (b - a);
        if (below(disk(x1), y) <= below(disk(x2), y)) b = x2;
        else a = x1;
      }
      lowest = std::min(lowest, below(disk(0.5 * (a + b)), y));
    }
    return lowest - 0.5 * curvature * y * y;
  };
  // The gap grows from 0 at the contact; bracket its crossing of sh, then bisect.
  double lo = 0, hi = 0.05;
  while (gap(hi) < scallop && hi < tool.radius) lo = hi, hi *= 1.5;
  hi = std::min(hi, tool.radius);
  if (gap(hi) < scallop) return tool.radius;  // the whole tool's width within sh (a vertical wall's side)
  for (int it = 0; it < 40; ++it) {
    const double mid = 0.5 * (lo + hi);
    (gap(mid) < scallop ? lo : hi) = mid;
  }
  return lo;
}

namespace {

constexpr double kSlopeStep = std::numbers::pi / 180, kAzimuthStep = std::numbers::pi / 90;

}  // namespace

SweptProfileTable::SweptProfileTable(const Tool& tool, double scallop) {
  slopes_ = 91;
  azimuths_ = 46;
  table_.resize(static_cast<std::size_t>(slopes_ * azimuths_));
  const Eigen::Vector3d axis = Eigen::Vector3d::UnitZ(), m = Eigen::Vector3d::UnitY();
  for (int i = 0; i < slopes_; ++i)
    for (int j = 0; j < azimuths_; ++j) {
      // A vertical wall has no level-ground reach: the last row repeats the one before it.
      const double s = std::min(i * kSlopeStep, 89.5 * kSlopeStep), beta = j * kAzimuthStep;
      const Eigen::Vector3d n(std::sin(s) * std::cos(beta), std::sin(s) * std::sin(beta), std::cos(s));
      Eigen::Vector3d along = m.cross(n);
      along.normalize();
      Eigen::Vector3d across = n.cross(along);
      if (across.dot(m) < 0) across = -across;
      SideReach& out = table_[static_cast<std::size_t>(i * azimuths_ + j)];
      out.minus = one_pass_reach(tool, n, axis, along, -across, 0.0, scallop);
      out.plus = one_pass_reach(tool, n, axis, along, across, 0.0, scallop);
    }
}

SideReach SweptProfileTable::reach(double slope, double beta) const {
  // Fold beta into [0, pi/2]: pi - beta is the same profile; -beta swaps the sides.
  beta = std::remainder(beta, 2 * std::numbers::pi);
  const bool swapped = beta < 0;
  beta = std::abs(beta);
  if (beta > std::numbers::pi / 2) beta = std::numbers::pi - beta;
  if (!std::isfinite(slope) || !std::isfinite(beta)) return {};  // no reach: the planner's floor
  const double x = std::clamp(slope / kSlopeStep, 0.0, slopes_ - 1.0), y = std::clamp(beta / kAzimuthStep, 0.0, azimuths_ - 1.0);
  const int i = std::min(static_cast<int>(x), slopes_ - 2), j = std::min(static_cast<int>(y), azimuths_ - 2);
  const auto at = [&](int a, int b) { return table_[static_cast<std::size_t>(a * azimuths_ + b)]; };
  // The smallest of the four neighbours, not a blend: near level ground the reach falls like
  // 1 / sqrt(s), and a straight line between two slopes a degree apart lies above it (4.5 % at
  // 1.5 deg), too wide a step; a degree's worth of caution costs little where the reach is flat.
  SideReach r{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  for (const int a : {i, i + 1})
    for (const int b : {j, j + 1}) {
      r.minus = std::min(r.minus, at(a, b).minus);
      r.plus = std::min(r.plus, at(a, b).plus);
    }
  if (swapped) std::swap(r.minus, r.plus);
  return r;
}

const SweptProfileTable& swept_profile_table(const Tool& tool, double scallop) {
  static std::mutex lock;
  static std::map<std::tuple<int, double, double, double>, std::unique_ptr<SweptProfileTable>> tables;
  const std::lock_guard<std::mutex> guard(lock);
  auto& t = tables[{static_cast<int>(tool.kind), tool.radius, tool.corner_radius, scallop}];
  if (!t) t = std::make_unique<SweptProfileTable>(tool, scallop);
  return *t;
}

}  // namespace drom::paths
