#include "paths/force_voxel_field.hpp"

#include <openvdb/openvdb.h>
#include <openvdb/tools/Interpolation.h>

#include <atomic>
#include <cmath>
#include <mutex>
#include <optional>

namespace drom::paths {

const char* interpolation_name(VoxelInterpolation i) {
  switch (i) {
    case VoxelInterpolation::trilinear: return "trilinear";
    case VoxelInterpolation::triquadratic: return "triquadratic";
    case VoxelInterpolation::tricubic: return "tricubic";
  }
  return "?";
}

namespace {
std::atomic<long> next_field_id{1};
std::once_flag vdb_once;

// Catmull-Rom weights for the 4 samples at offsets −1, 0, 1, 2 around t in [0, 1).
void catmull_rom(double t, double w[4]) {
  const double t2 = t * t, t3 = t2 * t;
  w[0] = 0.5 * (-t3 + 2 * t2 - t);
  w[1] = 0.5 * (3 * t3 - 5 * t2 + 2);
  w[2] = 0.5 * (-3 * t3 + 4 * t2 + t);
  w[3] = 0.5 * (t3 - t2);
}
}  // namespace

struct VoxelField::Impl {
  long id = 0;
  double voxel = 1;
  VoxelInterpolation interpolation = VoxelInterpolation::trilinear;
  openvdb::Vec3SGrid::Ptr force;
  openvdb::FloatGrid::Ptr nearest;
  float far = 1e30f;
};

VoxelField::VoxelField(const ObstacleCloud& obstacles, const KhatibParameters& k, const VoxelFieldSettings& settings) : impl_(std::make_unique<Impl>()) {
  std::call_once(vdb_once, [] { openvdb::initialize(); });
  impl_->id = next_field_id++;
  impl_->voxel = settings.voxel;
  impl_->interpolation = settings.interpolation;
  const double h = settings.voxel, r0 = k.influence_radius;
  impl_->far = static_cast<float>(r0);
  impl_->force = openvdb::Vec3SGrid::create(openvdb::Vec3s(0, 0, 0));
  impl_->nearest = openvdb::FloatGrid::create(impl_->far);
  auto force = impl_->force->getAccessor();
  auto nearest = impl_->nearest->getAccessor();
  // Keep every corner within r0 + one voxel diagonal of an obstacle: all 8 corners of every voxel that
  // has one within r0 (rule 4.3), so interpolation never mixes in a missing corner.
  const double reach = r0 + std::sqrt(3.0) * h;
  const int span = static_cast<int>(std::ceil(reach / h));
  for (std::size_t i = 0; i < obstacles.size(); ++i) {
    const Eigen::Vector3d& o = obstacles.points()[i];
    const openvdb::Coord c(static_cast<int>(std::lround(o.x() / h)), static_cast<int>(std::lround(o.y() / h)), static_cast<int>(std::lround(o.z() / h)));
    for (int dx = -span; dx <= span; ++dx)
      for (int dy = -span; dy <= span; ++dy)
        for (int dz = -span; dz <= span; ++dz) {
          const openvdb::Coord q = c.offsetBy(dx, dy, dz);
          const Eigen::Vector3d p(q.x() * h, q.y() * h, q.z() * h);
          const double r = (p - o).norm();
          if (r >= reach) continue;
          const Eigen::Vector3d f = khatib_force(p, o, k);
          const openvdb::Vec3s old = force.getValue(q);
          force.setValue(q, old + openvdb::Vec3s(static_cast<float>(f.x()), static_cast<float>(f.y()), static_cast<float>(f.z())));
          if (r < nearest.getValue(q)) nearest.setValue(q, static_cast<float>(r));
        }
  }
  if (settings.prune_material_side) {
    // Corners deeper than a voxel diagonal on the material side of their nearest obstacle.
    std::vector<openvdb::Coord> drop;
    for (auto it = impl_->force->cbeginValueOn(); it; ++it) {
      const openvdb::Coord q = it.getCoord();
      const Eigen::Vector3d p(q.x() * h, q.y() * h, q.z() * h);
      const int n = obstacles.nearest(p, obstacles.cell());
      if (n < 0) continue;
      if (obstacles.normals()[static_cast<std::size_t>(n)].dot(p - obstacles.points()[static_cast<std::size_t>(n)]) < -std::sqrt(3.0) * h) drop.push_back(q);
    }
    for (const auto& q : drop) {
      force.setValueOff(q, openvdb::Vec3s(0, 0, 0));
      nearest.setValueOff(q, impl_->far);
    }
    pruned_material_ = drop.size();
    impl_->force->pruneGrid();
    impl_->nearest->pruneGrid();
  }
}

VoxelField::~VoxelField() = default;

std::size_t VoxelField::stored_corners() const { return static_cast<std::size_t>(impl_->force->activeVoxelCount()); }
std::size_t VoxelField::memory_bytes() const { return static_cast<std::size_t>(impl_->force->memUsage() + impl_->nearest->memUsage()); }

FieldSample VoxelField::sample(const Eigen::Vector3d& p) const {
  // One accessor pair per thread and field (accessors cache the tree's path: most queries of a pose
  // fall in the same leaves).
  struct Cache {
    long id = 0;
    std::optional<openvdb::Vec3SGrid::ConstAccessor> force;
    std::optional<openvdb::FloatGrid::ConstAccessor> nearest;
  };
  thread_local Cache cache;
  if (cache.id != impl_->id) {
    cache.force.emplace(impl_->force->getConstAccessor());
    cache.nearest.emplace(impl_->nearest->getConstAccessor());
    cache.id = impl_->id;
  }
  const double h = impl_->voxel;
  const openvdb::Vec3R index(p.x() / h, p.y() / h, p.z() / h);
  openvdb::Vec3s f(0, 0, 0);
  float near = impl_->far;
  switch (impl_->interpolation) {
    case VoxelInterpolation::trilinear:
      openvdb::tools::BoxSampler::sample(*cache.force, index, f);
      break;
    case VoxelInterpolation::triquadratic:
      openvdb::tools::QuadraticSampler::sample(*cache.force, index, f);
      break;
    case VoxelInterpolation::tricubic: {
      const int ix = static_cast<int>(std::floor(index.x())), iy = static_cast<int>(std::floor(index.y())), iz = static_cast<int>(std::floor(index.z()));
      double wx[4], wy[4], wz[4];
      catmull_rom(index.x() - ix, wx);
      catmull_rom(index.y() - iy, wy);
      catmull_rom(index.z() - iz, wz);
      openvdb::Vec3d sum(0, 0, 0);
      for (int a = 0; a < 4; ++a)
        for (int b = 0; b < 4; ++b)
          for (int c = 0; c < 4; ++c) {
            const openvdb::Vec3s v = cache.force->getValue(openvdb::Coord(ix + a - 1, iy + b - 1, iz + c - 1));
            sum += openvdb::Vec3d(v) * (wx[a] * wy[b] * wz[c]);
          }
      f = openvdb::Vec3s(sum);
      break;
    }
  }
  openvdb::tools::BoxSampler::sample(*cache.nearest, index, near);
  FieldSample s;
  s.force = Eigen::Vector3d(f.x(), f.y(), f.z());
  s.nearest = near;
  s.active = s.force.squaredNorm() > 0 ? 1 : 0;
  return s;
}

}  // namespace drom::paths
