#include "paths/orient/clearance_check.hpp"

#include <Eigen/Geometry>
#include <openvdb/openvdb.h>
#include <openvdb/tools/MeshToVolume.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <mutex>
#include <numbers>

namespace drom::paths {

namespace {

// The closest point of triangle abc to p (Ericson, Real-Time Collision Detection §5.1.5).
Eigen::Vector3d closest_on_triangle(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c) {
  const Eigen::Vector3d ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return a;
  const Eigen::Vector3d bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + d1 / (d1 - d3) * ab;
  const Eigen::Vector3d cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + d2 / (d2 - d6) * ac;
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) return b + (d4 - d3) / ((d4 - d3) + (d5 - d6)) * (c - b);
  const double denom = 1 / (va + vb + vc);
  return a + ab * (vb * denom) + ac * (vc * denom);
}

std::once_flag openvdb_initialised;

}  // namespace

struct ObstacleDistance::Impl {
  double voxel = 0.5;
  TriangleSoup soup;
  std::vector<Eigen::Vector3d> normals;
  openvdb::Int32Grid::Ptr index;
  openvdb::FloatGrid::Ptr distance;
};

ObstacleDistance::ObstacleDistance(const TriangleSoup& soup, double voxel, double band) : impl_(std::make_unique<Impl>()), band_(band) {
  std::call_once(openvdb_initialised, [] { openvdb::initialize(); });
  impl_->voxel = voxel;
  impl_->soup = soup;
  std::vector<openvdb::Vec3s> points;
  std::vector<openvdb::Vec3I> triangles;
  for (const auto& v : soup.vertices) points.emplace_back(static_cast<float>(v.x() / voxel), static_cast<float>(v.y() / voxel), static_cast<float>(v.z() / voxel));
  for (const auto& t : soup.triangles) {
    triangles.emplace_back(static_cast<openvdb::Index32>(t[0]), static_cast<openvdb::Index32>(t[1]), static_cast<openvdb::Index32>(t[2]));
    const Eigen::Vector3d n = (soup.vertices[t[1]] - soup.vertices[t[0]]).cross(soup.vertices[t[2]] - soup.vertices[t[0]]);
    impl_->normals.push_back(n.norm() > 0 ? Eigen::Vector3d(n.normalized()) : Eigen::Vector3d::Zero());
  }
  const auto transform = openvdb::math::Transform::createLinearTransform(voxel);
  openvdb::tools::QuadAndTriangleDataAdapter<openvdb::Vec3s, openvdb::Vec3I> mesh(points, triangles);
  impl_->index = openvdb::Int32Grid::create(openvdb::util::INVALID_IDX);
  impl_->index->setTransform(transform);
  const float width = static_cast<float>(band / voxel + 2);
  impl_->distance = openvdb::tools::meshToVolume<openvdb::FloatGrid>(mesh, *transform, width, width, openvdb::tools::UNSIGNED_DISTANCE_FIELD,
                                                                     impl_->index.get());
}

ObstacleDistance::~ObstacleDistance() = default;

std::size_t ObstacleDistance::active_voxels() const { return static_cast<std::size_t>(impl_->index->activeVoxelCount()); }

double ObstacleDistance::distance(const Eigen::Vector3d& p) const {
  const double h = impl_->voxel;
  const openvdb::Coord base(static_cast<int>(std::floor(p.x() / h)), static_cast<int>(std::floor(p.y() / h)), static_cast<int>(std::floor(p.z() / h)));
  // Unregistered: a registered accessor's construction locks the tree's registry, which the parallel
  // pose checks would contend on.
  openvdb::tree::ValueAccessor<const openvdb::Int32Tree, false> acc(impl_->index->tree());
  int seen[8];
  int count = 0;
  for (int c = 0; c < 8; ++c) {
    const openvdb::Coord q = base.offsetBy(c & 1, (c >> 1) & 1, (c >> 2) & 1);
    openvdb::Int32 id;
    if (!acc.probeValue(q, id) || id < 0) continue;
    if (std::find(seen, seen + count, id) == seen + count) seen[count++] = id;
  }
  if (count == 0) return band_;
  double best = 1e300, best_signed = band_, best_face = -1;
  for (int k = 0; k < count; ++k) {
    const auto& t = impl_->soup.triangles[static_cast<std::size_t>(seen[k])];
    const Eigen::Vector3d q = closest_on_triangle(p, impl_->soup.vertices[t[0]], impl_->soup.vertices[t[1]], impl_->soup.vertices[t[2]]);
    const double d = (p - q).norm();
    const double along = (p - q).dot(impl_->normals[static_cast<std::size_t>(seen[k])]);
    const double face = d > 0 ? std::abs(along) / d : 1;
    // Equally near triangles (an edge, a vertex): the one seen most face-on decides the side.
    if (d < best - 1e-9 || (d < best + 1e-9 && face > best_face)) {
      best = std::min(best, d);
      best_face = face;
      // Behind a face: negative. Beside an open edge (a blade's tip, a patch's border) the side is not
      // defined: the unsigned distance alone then measures the overlap.
      best_signed = along < 0 && face > 0.9 ? -d : d;
    }
  }
  return std::min(best_signed, band_);
}

ClearanceChecker::ClearanceChecker(const OrientScene& scene, const ClearanceSettings& settings) : scene_(scene), settings_(settings) {
  const ToolAssembly& tool = scene.tool;
  const RevolvedProfile body = body_profile(tool);
  // Wide enough that any clearance under 5 mm (over check.required) is measured; a larger one reads as
  // at least 5 mm. 10 mm cost the full impeller's band 40 % more time to build.
  const double band = body.max_radius() + std::max(settings.required, 0.0) + 5;
  distance_ = std::make_unique<ObstacleDistance>(scene_check_triangles(scene, std::min(1.0, 2 * settings.voxel)), settings.voxel, band);
  // Covering spheres of the body, heights above the pivot.
  const double z0 = body.z.front(), z1 = body.z.back();
  const int n = std::max(1, static_cast<int>(std::ceil((z1 - z0) / settings.axial_step)));
  const double dz = (z1 - z0) / n;
  for (int i = 0; i < n; ++i) {
    const double a = z0 + i * dz, b = a + dz;
    double rho = std::max(body.radius_at(a), body.radius_at(b));
    for (std::size_t k = 0; k < body.z.size(); ++k)
      if (body.z[k] >= a && body.z[k] <= b) rho = std::max(rho, body.radius[k]);
    slabs_.emplace_back(0.5 * (a + b) - tool.cutter.pivot_height(), std::hypot(rho, 0.5 * dz));
  }
  const double R = tool.cutter.radius;
  cutter_reach_ = std::hypot(R, tool.flute_length - tool.cutter.pivot_height()) + tool.cutter.pivot_height();
  part_samples_ = ObstacleCloud({}, {}, cutter_reach_ / 2);
  for (const auto& p : scene.part_surfaces) part_samples_.append(ObstacleCloud::from_patch(p.surface, settings.gouge_spacing, p.flip, cutter_reach_ / 2));
}

ClearanceChecker::~ClearanceChecker() = default;

PoseCheck ClearanceChecker::check(const Eigen::Vector3d& cl, const Eigen::Vector3d& axis) const {
  PoseCheck c;
  const ToolAssembly& tool = scene_.tool;
  // Every slab is measured. (Skipping slabs by the distance's Lipschitz bound saved 0.3 s a vein, but
  // the signed reading flips around a patch's open border, and a skipped slab behind one would hide.)
  for (const auto& [height, radius] : slabs_) {
    const double margin = distance_->distance(cl + height * axis) - radius;
    if (margin < c.clearance) {
      c.clearance = margin;
      c.clearance_height = height + tool.cutter.pivot_height();
    }
  }
  // The cutter against the check surfaces: the ball, or the torus covered by a sphere over its flat
  // bottom (radius √((R − r)² + r²) about the pivot) and 16 spheres along its tube (on the corner
  // circle, radius √(r² + (chord/2)²)), and the flutes.
  const double R = tool.cutter.radius, r = tool.cutter.corner_radius;
  double into_check = -(distance_->distance(cl) - (R == r ? R : std::sqrt((R - r) * (R - r) + r * r)));
  if (R != r) {
    constexpr int kTube = 16;
    const double chord = 2 * (R - r) * std::sin(std::numbers::pi / kTube), tube = std::sqrt(r * r + 0.25 * chord * chord);
    const Eigen::Vector3d e1 = axis.unitOrthogonal(), e2 = axis.cross(e1);
    for (int k = 0; k < kTube; ++k) {
      const double phi = 2 * std::numbers::pi * k / kTube;
      const Eigen::Vector3d centre = cl + (R - r) * (std::cos(phi) * e1 + std::sin(phi) * e2);
      into_check = std::max(into_check, -(distance_->distance(centre) - tube));
    }
  }
  for (double z = 0.5; z <= tool.flute_length - tool.cutter.pivot_height(); z += 0.5)
    into_check = std::max(into_check, -(distance_->distance(cl + z * axis) - std::hypot(R, 0.25)));
  c.gouge_depth = std::max(0.0, into_check);
  // The cutter against the part surfaces: exact signed distance of each sample to the cutter.
  Eigen::Matrix3d frame;
  frame.col(2) = axis;
  frame.col(0) = axis.unitOrthogonal();
  frame.col(1) = axis.cross(frame.col(0));
  const double reach2 = cutter_reach_ * cutter_reach_;
  const double R2 = R * R, below = -tool.cutter.pivot_height(), above = tool.flute_length - tool.cutter.pivot_height();
  part_samples_.for_each_within(cl, cutter_reach_, [&](int i) {
    const Eigen::Vector3d d = part_samples_.points()[static_cast<std::size_t>(i)] - cl;
    const double d2 = d.squaredNorm();
    if (d2 > reach2) return;
    // Only a sample inside the cutter's cylinder (radius R, tip to flutes) can be inside the cutter.
    const double along = d.dot(axis);
    if (along < below || along > above || d2 - along * along > R2) return;
    const double sd = cutter_signed_distance(tool, frame.transpose() * d);
    if (-sd > c.gouge_depth) c.gouge_depth = -sd;
  });
  return c;
}

ClearanceReport ClearanceChecker::check_all(const std::vector<std::vector<Eigen::Vector3d>>& cl, const std::vector<std::vector<Eigen::Vector3d>>& axes,
                                            const std::vector<std::vector<double>>& s) const {
  ClearanceReport r;
  r.passes.resize(cl.size());
  // Poses are independent: checked in parallel, then gathered in order.
  tbb::parallel_for(std::size_t(0), cl.size(), [&](std::size_t p) {
    r.passes[p].resize(cl[p].size());
    for (std::size_t i = 0; i < cl[p].size(); ++i) r.passes[p][i] = check(cl[p][i], axes[p][i]);
  });
  for (std::size_t p = 0; p < cl.size(); ++p) {
    for (std::size_t i = 0; i < cl[p].size(); ++i) {
      const PoseCheck& c = r.passes[p][i];
      ++r.poses;
      r.worst_clearance = std::min(r.worst_clearance, c.clearance);
      r.worst_gouge = std::max(r.worst_gouge, c.gouge_depth);
      if (c.clearance < settings_.required)
        r.collisions.push_back({p, i, s[p][i], c.clearance, "shank/holder clearance " + std::to_string(c.clearance) + " mm at " + std::to_string(c.clearance_height) + " mm above the tip"});
      if (c.gouge_depth > settings_.gouge_tolerance)
        r.gouges.push_back({p, i, s[p][i], c.gouge_depth, "cutter " + std::to_string(c.gouge_depth) + " mm into a surface"});
    }
  }
  return r;
}

}  // namespace drom::paths
