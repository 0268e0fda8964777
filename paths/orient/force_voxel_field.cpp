#include "paths/orient/force_voxel_field.hpp"

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
using Vec4Grid = openvdb::Grid<openvdb::tree::Tree4<openvdb::Vec4s, 5, 4, 3>::Type>;
std::once_flag vdb_once;

// Trilinear interpolation of a grid's values at an index-space point, the 8 corners read from one leaf
// when they share it (7 in 8 queries of a leaf's 8³ voxels along each axis), which the pose loop's
// 500 queries per right-hand side spend most of their time in otherwise. Inactive corners count with
// their stored value, as OpenVDB's BoxSampler counts them.
template <class Accessor>
typename Accessor::ValueType trilinear(const Accessor& acc, const openvdb::Vec3d& index) {
  using Leaf = typename Accessor::TreeType::LeafNodeType;
  using Value = typename Accessor::ValueType;
  const openvdb::Coord ijk(static_cast<int>(std::floor(index.x())), static_cast<int>(std::floor(index.y())), static_cast<int>(std::floor(index.z())));
  const double fx = index.x() - ijk.x(), fy = index.y() - ijk.y(), fz = index.z() - ijk.z();
  Value v[8];
  constexpr int last = static_cast<int>(Leaf::DIM) - 1;
  if ((ijk.x() & last) != last && (ijk.y() & last) != last && (ijk.z() & last) != last) {
    const Leaf* leaf = acc.probeConstLeaf(ijk);
    if (!leaf) return acc.getValue(ijk);  // a tile: one value over all 8 corners
    const openvdb::Index o = Leaf::coordToOffset(ijk);
    constexpr openvdb::Index sx = 1u << (2 * Leaf::LOG2DIM), sy = 1u << Leaf::LOG2DIM;
    for (int c = 0; c < 8; ++c) v[c] = leaf->getValue(o + ((c & 1) ? sx : 0) + ((c & 2) ? sy : 0) + ((c & 4) ? 1 : 0));
  } else {
    for (int c = 0; c < 8; ++c) v[c] = acc.getValue(ijk.offsetBy(c & 1, (c >> 1) & 1, (c >> 2) & 1));
  }
  const auto lerp = [](const Value& a, const Value& b, double t) { return a + (b - a) * static_cast<float>(t); };
  const Value x00 = lerp(v[0], v[1], fx), x10 = lerp(v[2], v[3], fx), x01 = lerp(v[4], v[5], fx), x11 = lerp(v[6], v[7], fx);
  return lerp(lerp(x00, x10, fy), lerp(x01, x11, fy), fz);
}

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
  Vec4Grid::Ptr grid;  // (F1, nearest obstacle distance) per corner
  float far = 1e30f;
  const ObstacleCloud* obstacles = nullptr;
  KhatibParameters khatib;
  double near_inner = 0, near_outer = 0;  // mm: exact sum within inner, blended out to outer
};

VoxelField::VoxelField(const ObstacleCloud& obstacles, const KhatibParameters& k, const VoxelFieldSettings& settings) : impl_(std::make_unique<Impl>()) {
  std::call_once(vdb_once, [] { openvdb::initialize(); });
  impl_->id = next_field_id++;
  impl_->voxel = settings.voxel;
  impl_->interpolation = settings.interpolation;
  const double h = settings.voxel, r0 = k.influence_radius;
  impl_->far = static_cast<float>(r0);
  impl_->obstacles = &obstacles;
  impl_->khatib = k;
  impl_->near_outer = std::max(0.0, settings.near_field) * h;
  impl_->near_inner = impl_->near_outer / 2;
  impl_->grid = Vec4Grid::create(openvdb::Vec4s(0, 0, 0, impl_->far));
  auto grid = impl_->grid->getAccessor();
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
          const openvdb::Vec4s old = grid.getValue(q);
          grid.setValue(q, openvdb::Vec4s(old[0] + static_cast<float>(f.x()), old[1] + static_cast<float>(f.y()), old[2] + static_cast<float>(f.z()),
                                          std::min(old[3], static_cast<float>(r))));
        }
  }
  if (settings.prune_material_side) {
    // Corners deeper than a voxel diagonal on the material side of their nearest obstacle.
    std::vector<openvdb::Coord> drop;
    for (auto it = impl_->grid->cbeginValueOn(); it; ++it) {
      const openvdb::Coord q = it.getCoord();
      const Eigen::Vector3d p(q.x() * h, q.y() * h, q.z() * h);
      const int n = obstacles.nearest(p, obstacles.cell());
      if (n < 0) continue;
      if (obstacles.normals()[static_cast<std::size_t>(n)].dot(p - obstacles.points()[static_cast<std::size_t>(n)]) < -std::sqrt(3.0) * h) drop.push_back(q);
    }
    // The force goes, the nearest distance stays: a node that got into the material is still near an
    // obstacle, so the exact near field still holds it.
    for (const auto& q : drop) grid.setValueOff(q, openvdb::Vec4s(0, 0, 0, grid.getValue(q)[3]));
    pruned_material_ = drop.size();
    impl_->grid->pruneGrid();
  }
}

VoxelField::~VoxelField() = default;

std::size_t VoxelField::stored_corners() const { return static_cast<std::size_t>(impl_->grid->activeVoxelCount()); }
std::size_t VoxelField::memory_bytes() const { return static_cast<std::size_t>(impl_->grid->memUsage()); }

namespace {
// One accessor per thread and field (an accessor caches the tree's path: most queries of a pose fall
// in the same leaves).
// Unregistered: a registered accessor is reset by its tree's destructor from whichever thread destroys
// the field, which would race with another thread rebinding its own.
using Vec4Accessor = openvdb::tree::ValueAccessor<const Vec4Grid::TreeType, false>;
const Vec4Accessor& accessor(long id, const Vec4Grid& grid) {
  thread_local long bound = 0;
  thread_local std::optional<Vec4Accessor> cache;
  if (bound != id) {
    cache.emplace(grid.tree());
    bound = id;
  }
  return *cache;
}
}  // namespace

Eigen::Vector3d VoxelField::grid_force(const Eigen::Vector3d& p, double* nearest) const {
  const Vec4Accessor& acc = accessor(impl_->id, *impl_->grid);
  const double h = impl_->voxel;
  const openvdb::Vec3d index(p.x() / h, p.y() / h, p.z() / h);
  openvdb::Vec4s v = trilinear(acc, index);
  if (nearest) *nearest = v[3];
  switch (impl_->interpolation) {
    case VoxelInterpolation::trilinear:
      break;
    case VoxelInterpolation::triquadratic:
      openvdb::tools::QuadraticSampler::sample(acc, index, v);
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
            const openvdb::Vec4s corner = acc.getValue(openvdb::Coord(ix + a - 1, iy + b - 1, iz + c - 1));
            sum += openvdb::Vec3d(corner[0], corner[1], corner[2]) * (wx[a] * wy[b] * wz[c]);
          }
      v = openvdb::Vec4s(static_cast<float>(sum[0]), static_cast<float>(sum[1]), static_cast<float>(sum[2]), v[3]);
      break;
    }
  }
  return Eigen::Vector3d(v[0], v[1], v[2]);
}

Eigen::Vector3d VoxelField::near_corrected(const Eigen::Vector3d& p, const Eigen::Vector3d& grid, double nearest) const {
  if (nearest >= impl_->near_outer) return grid;
  const Eigen::Vector3d exact = repulsive_force(*impl_->obstacles, p, impl_->khatib, Aggregation::F1).force;
  if (nearest <= impl_->near_inner) return exact;
  // Smoothstep from the exact sum at near_inner to the grid at near_outer: C¹ in the distance.
  const double t = (nearest - impl_->near_inner) / (impl_->near_outer - impl_->near_inner), w = t * t * (3 - 2 * t);
  return w * grid + (1 - w) * exact;
}

Eigen::Vector3d VoxelField::force(const Eigen::Vector3d& p) const {
  double nearest = 0;
  const Eigen::Vector3d grid = grid_force(p, &nearest);
  return near_corrected(p, grid, nearest);
}

FieldSample VoxelField::sample(const Eigen::Vector3d& p) const {
  FieldSample s;
  double nearest = 0;
  const Eigen::Vector3d grid = grid_force(p, &nearest);
  s.force = near_corrected(p, grid, nearest);
  s.nearest = nearest;
  s.active = s.force.squaredNorm() > 0 ? 1 : 0;
  return s;
}

}  // namespace drom::paths
