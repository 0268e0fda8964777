#include "paths/copy/visibility.hpp"

#include "geometry/cloud_bins.hpp"
#include "geometry/point_cloud.hpp"

#include <tbb/parallel_for.h>

#include <bit>
#include <cmath>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace drom::paths {

namespace {

constexpr double kDegree = std::numbers::pi / 180;

}  // namespace

Directions direction_grid(double phi_step, double theta_step) {
  if (!(phi_step > 0 && phi_step <= 360) || !(theta_step > 0 && theta_step <= 180)) throw std::invalid_argument("direction grid: steps in (0, 360] and (0, 180] degrees");
  const int nphi = static_cast<int>(std::floor(360 / phi_step + 1e-9)), ntheta = static_cast<int>(std::floor(180 / theta_step + 1e-9));
  Directions d;
  d.grid_count = nphi * ntheta;
  for (int j = 0; j < ntheta; ++j) {
    const double theta = j * theta_step;
    for (int i = 0; i < nphi; ++i) {
      if (j == 0 && i > 0) break;  // the pole, once
      const double phi = i * phi_step;
      d.unit.emplace_back(std::sin(theta * kDegree) * std::cos(phi * kDegree), std::sin(theta * kDegree) * std::sin(phi * kDegree), std::cos(theta * kDegree));
      d.phi.push_back(phi), d.theta.push_back(theta);
    }
  }
  return d;
}

std::vector<Eigen::Vector3d> obstacle_surface(const Obstacle& o, double spacing) {
  if (!(spacing > 0)) throw std::invalid_argument("obstacle surface: the spacing must be positive");
  std::vector<Eigen::Vector3d> out;
  const auto count = [&](double length) { return std::max(1, static_cast<int>(std::ceil(length / spacing))); };
  if (o.kind == Obstacle::Kind::box) {
    const Eigen::Vector3d size = o.hi - o.lo;
    // Each face sampled on its own grid, edges included.
    for (int axis = 0; axis < 3; ++axis) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      const int nu = count(size[u]), nv = count(size[v]);
      for (const double level : {o.lo[axis], o.hi[axis]}) {
        if (axis == 2 && level == o.lo[axis] && !o.bottom) continue;
        for (int a = 0; a <= nu; ++a)
          for (int b = 0; b <= nv; ++b) {
            Eigen::Vector3d p;
            p[axis] = level, p[u] = o.lo[u] + size[u] * a / nu, p[v] = o.lo[v] + size[v] * b / nv;
            out.push_back(p);
          }
      }
    }
  } else {
    const double radius = o.hi.x(), height = o.hi.z() - o.lo.z();
    const int around = count(2 * std::numbers::pi * radius), along = count(height), rings = count(radius);
    for (int a = 0; a < around; ++a) {
      const double t = 2 * std::numbers::pi * a / around;
      for (int b = 0; b <= along; ++b) out.emplace_back(o.lo.x() + radius * std::cos(t), o.lo.y() + radius * std::sin(t), o.lo.z() + height * b / along);
      for (int c = 0; c <= rings; ++c)
        for (const double z : {o.lo.z(), o.hi.z()}) out.emplace_back(o.lo.x() + radius * c / rings * std::cos(t), o.lo.y() + radius * c / rings * std::sin(t), z);
    }
  }
  return out;
}

int VisibilityMatrix::column_count(int direction) const {
  int n = 0;
  for (const auto w : columns[static_cast<std::size_t>(direction)]) n += std::popcount(w);
  return n;
}

Reach machine_reach(const machine::Kinematics& kin, const Eigen::Vector3d& direction, const Eigen::Vector3d& lo, const Eigen::Vector3d& hi, bool check_travel) {
  const machine::Machine& m = kin.machine();
  Reach out;
  const machine::IkBranches centre = kin.inverse({0.5 * (lo + hi), direction});
  if (centre.count == 0) {
    out.ok = false;
    out.why = "the chain cannot orient the tool this way";
    return out;
  }
  std::string first_why;
  for (int b = 0; b < centre.count; ++b) {
    machine::Joints q = centre.joints[static_cast<std::size_t>(b)];
    std::string why;
    // Rotary strokes, each angle tried a turn either way.
    for (int j = 3; j < m.joint_count() && why.empty(); ++j) {
      const auto& axis = m.axes[static_cast<std::size_t>(j)];
      if (axis.continuous) continue;
      bool within = false;
      for (const double turn : {0.0, 2 * std::numbers::pi, -2 * std::numbers::pi})
        if (axis.within(q[j] + turn)) {
          q[j] += turn;
          within = true;
          break;
        }
      if (!within) why = machine::describe_joint_value(m, j, q[j]) + " beyond its stroke";
    }
    if (why.empty() && check_travel) {
      for (int corner = 0; corner < 8 && why.empty(); ++corner) {
        const Eigen::Vector3d tip((corner & 1) ? hi.x() : lo.x(), (corner & 2) ? hi.y() : lo.y(), (corner & 4) ? hi.z() : lo.z());
        const machine::IkBranches at = kin.inverse({tip, direction});
        for (int c = 0; c < at.count; ++c) {
          const machine::Joints& p = at.joints[static_cast<std::size_t>(c)];
          bool same = true;
          for (int j = 3; j < m.joint_count(); ++j) same = same && std::abs(std::remainder(p[j] - q[j], 2 * std::numbers::pi)) < 1e-9;
          if (!same) continue;
          for (int j = 0; j < 3 && why.empty(); ++j)
            if (!m.axes[static_cast<std::size_t>(j)].within(kin.stroke_value(j, p))) why = machine::describe_joint_value(m, j, kin.stroke_value(j, p)) + " beyond its travel at a corner of the cloud's box";
        }
      }
    }
    if (why.empty()) {
      if (m.joint_count() >= 5) out.rotary = Eigen::Vector2d(q[3], q[4]) / kDegree;
      return out;
    }
    if (first_why.empty()) first_why = why;
  }
  out.ok = false;
  out.why = first_why;
  return out;
}

struct BodyCheck::Impl {
  Eigen::Matrix3d q;
  geometry::CloudBins bins;
  ToolAssembly tool;
  Eigen::Vector3d axis;
  double graze = 0;
};

BodyCheck::BodyCheck(std::span<const Eigen::Vector3d> collision, const Eigen::Vector3d& direction, const ToolAssembly& tool, double graze) : impl_(std::make_unique<Impl>()) {
  impl_->q = geometry::frame_along(direction);
  impl_->axis = direction.normalized();
  impl_->tool = tool;
  impl_->graze = graze;
  impl_->bins = geometry::CloudBins(geometry::rotated(collision, impl_->q), std::max(0.25, tool.cutter.radius / 2));
}

BodyCheck::~BodyCheck() = default;
BodyCheck::BodyCheck(BodyCheck&&) noexcept = default;

bool BodyCheck::clear(const Eigen::Vector3d& p, const Eigen::Vector3d& n) const {
  const ToolAssembly& t = impl_->tool;
  const Tool& c = t.cutter;
  // The tool tip with the cutter touching p along n, in the direction's drop frame.
  const Eigen::Vector3d tip = impl_->q * cutter_location(p, n, c, impl_->axis);
  const double tube = c.kind == ToolKind::ball ? c.radius : c.corner_radius;
  // The body above the cutter's tube centre (the upper half of a ball, and the flutes), the shank,
  // the holder: each a cylinder up from its base, nothing strictly inside it but grazes.
  if (impl_->bins.any_above(tip.x(), tip.y(), c.radius - impl_->graze, tip.z() + tube + impl_->graze)) return false;
  if (t.shank() > c.radius && impl_->bins.any_above(tip.x(), tip.y(), t.shank() - impl_->graze, tip.z() + t.flutes())) return false;
  if (t.has_holder() && impl_->bins.any_above(tip.x(), tip.y(), t.holder_reach() - impl_->graze, tip.z() + t.gauge_length)) return false;
  return true;
}

VisibilityMatrix visibility_matrix(std::span<const Eigen::Vector3d> collision, std::span<const Eigen::Vector3d> points, std::span<const Eigen::Vector3d> normals,
                                   const VisibilitySettings& s) {
  if (points.size() != normals.size()) throw std::invalid_argument("visibility: one normal per point");
  if (!(s.cone_min >= 0 && s.cone_min < s.cone_max && s.cone_max <= 90)) throw std::invalid_argument("visibility: the cone needs 0 <= v1 < v2 <= 90 degrees");
  VisibilityMatrix m;
  m.directions = direction_grid(s.phi_step, s.theta_step);
  m.points = static_cast<int>(points.size());
  const std::size_t directions = m.directions.unit.size(), words = (points.size() + 63) / 64;
  m.columns.assign(directions, std::vector<std::uint64_t>(words, 0));
  m.reachable.assign(directions, 1);
  m.rotary.assign(directions, Eigen::Vector2d::Zero());
  // 3 first (it is cheap and empties whole columns), then 1 and 2 per reachable direction.
  const geometry::Box3 box = geometry::bounding_box(points);
  if (s.machine)
    for (std::size_t j = 0; j < directions; ++j) {
      const Reach r = machine_reach(*s.machine, m.directions.unit[j], box.lo, box.hi, s.check_travel);
      m.reachable[j] = r.ok;
      m.rotary[j] = r.rotary;
    }
  const double cos_min = std::cos(s.cone_min * kDegree), cos_max = std::cos(s.cone_max * kDegree);
  std::vector<long long> visible(directions, 0), hit(directions, 0);
  tbb::parallel_for(std::size_t(0), directions, [&](std::size_t j) {
    if (!m.reachable[j]) return;
    const Eigen::Vector3d& d = m.directions.unit[j];
    std::vector<int> in_cone;
    for (std::size_t i = 0; i < points.size(); ++i) {
      const double c = d.dot(normals[i]);
      if (c <= cos_min + 1e-12 && c >= cos_max - 1e-12) in_cone.push_back(static_cast<int>(i));
    }
    visible[j] = static_cast<long long>(in_cone.size());
    if (in_cone.empty()) return;
    const BodyCheck body(collision, d, s.tool, s.graze);
    auto& column = m.columns[j];
    for (const int i : in_cone) {
      if (body.clear(points[static_cast<std::size_t>(i)], normals[static_cast<std::size_t>(i)])) column[static_cast<std::size_t>(i) >> 6] |= std::uint64_t{1} << (i & 63);
      else ++hit[j];
    }
  });
  for (std::size_t j = 0; j < directions; ++j) m.tool_visible += visible[j], m.collisions += hit[j];
  return m;
}

}  // namespace drom::paths
