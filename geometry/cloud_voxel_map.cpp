#include "geometry/cloud_voxel_map.hpp"

#include <Eigen/Eigenvalues>
#include <openvdb/openvdb.h>

#include <algorithm>
#include <tuple>
#include <cmath>
#include <stdexcept>

namespace drom::geometry {

namespace {

openvdb::Coord voxel_of(const Eigen::Vector3d& p, double edge) {
  return openvdb::Coord(static_cast<openvdb::Int32>(std::floor(p.x() / edge)), static_cast<openvdb::Int32>(std::floor(p.y() / edge)),
                        static_cast<openvdb::Int32>(std::floor(p.z() / edge)));
}

}  // namespace

struct CloudVoxelMap::Impl {
  openvdb::Int32Grid::Ptr count;
  openvdb::Vec3DGrid::Ptr sum, square, cross;  // sum of q; of (qx², qy², qz²); of (qx qy, qx qz, qy qz), q = p - corner
};

CloudVoxelMap::CloudVoxelMap(std::span<const Eigen::Vector3d> points, double edge) : impl_(std::make_unique<Impl>()), edge_(edge) {
  if (!(edge > 0) || !std::isfinite(edge)) throw std::invalid_argument("CloudVoxelMap: the voxel edge must be positive");
  openvdb::initialize();
  impl_->count = openvdb::Int32Grid::create(0);
  impl_->sum = openvdb::Vec3DGrid::create(openvdb::Vec3d(0));
  impl_->square = openvdb::Vec3DGrid::create(openvdb::Vec3d(0));
  impl_->cross = openvdb::Vec3DGrid::create(openvdb::Vec3d(0));
  auto count = impl_->count->getAccessor();
  auto sum = impl_->sum->getAccessor();
  auto square = impl_->square->getAccessor();
  auto cross = impl_->cross->getAccessor();
  for (const auto& p : points) {
    if (!p.allFinite()) throw std::invalid_argument("CloudVoxelMap: a point is not finite");
    const openvdb::Coord c = voxel_of(p, edge);
    const Eigen::Vector3d q = p - Eigen::Vector3d(c.x(), c.y(), c.z()) * edge;
    count.setValue(c, count.getValue(c) + 1);
    sum.setValue(c, sum.getValue(c) + openvdb::Vec3d(q.x(), q.y(), q.z()));
    square.setValue(c, square.getValue(c) + openvdb::Vec3d(q.x() * q.x(), q.y() * q.y(), q.z() * q.z()));
    cross.setValue(c, cross.getValue(c) + openvdb::Vec3d(q.x() * q.y(), q.x() * q.z(), q.y() * q.z()));
  }
}

CloudVoxelMap::~CloudVoxelMap() = default;
CloudVoxelMap::CloudVoxelMap(CloudVoxelMap&&) noexcept = default;
CloudVoxelMap& CloudVoxelMap::operator=(CloudVoxelMap&&) noexcept = default;

std::size_t CloudVoxelMap::full_voxels() const { return static_cast<std::size_t>(impl_->count->activeVoxelCount()); }

int CloudVoxelMap::count(const Eigen::Vector3d& p) const { return impl_->count->getConstAccessor().getValue(voxel_of(p, edge_)); }

bool CloudVoxelMap::full(const Eigen::Vector3d& p) const { return count(p) > 0; }

std::vector<CloudVoxel> CloudVoxelMap::voxels() const {
  std::vector<CloudVoxel> out;
  out.reserve(full_voxels());
  auto sum = impl_->sum->getConstAccessor();
  auto square = impl_->square->getConstAccessor();
  auto cross = impl_->cross->getConstAccessor();
  for (auto it = impl_->count->cbeginValueOn(); it; ++it) {
    const openvdb::Coord c = it.getCoord();
    CloudVoxel v;
    v.coord = Eigen::Vector3i(c.x(), c.y(), c.z());
    v.count = *it;
    const double n = v.count;
    const openvdb::Vec3d s = sum.getValue(c), q2 = square.getValue(c), qc = cross.getValue(c);
    const Eigen::Vector3d mean(s.x() / n, s.y() / n, s.z() / n);
    v.barycentre = mean + Eigen::Vector3d(c.x(), c.y(), c.z()) * edge_;
    if (v.count >= 3) {
      Eigen::Matrix3d cov;
      cov << q2.x() / n, qc.x() / n, qc.y() / n, qc.x() / n, q2.y() / n, qc.z() / n, qc.y() / n, qc.z() / n, q2.z() / n;
      cov -= mean * mean.transpose();
      const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov);
      v.normal = eig.eigenvectors().col(0);
      v.planarity = eig.eigenvalues()(1) > 0 ? std::max(0.0, eig.eigenvalues()(0)) / eig.eigenvalues()(1) : 0;
    }
    out.push_back(v);
  }
  std::sort(out.begin(), out.end(), [](const CloudVoxel& a, const CloudVoxel& b) {
    return std::tie(a.coord.x(), a.coord.y(), a.coord.z()) < std::tie(b.coord.x(), b.coord.y(), b.coord.z());
  });
  return out;
}

}  // namespace drom::geometry
