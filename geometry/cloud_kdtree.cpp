#include "geometry/cloud_kdtree.hpp"

#include <nanoflann.hpp>

#include <cmath>
#include <stdexcept>

namespace drom::geometry {

namespace {

struct Dataset {
  std::vector<double> coordinates;  // point-major, `dimensions` per point
  int dimensions = 3;
  std::size_t kdtree_get_point_count() const { return coordinates.size() / static_cast<std::size_t>(dimensions); }
  double kdtree_get_pt(std::size_t i, std::size_t d) const { return coordinates[i * static_cast<std::size_t>(dimensions) + d]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};

using Tree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, Dataset>, Dataset, -1, std::uint32_t>;

// Collects every index closer than the radius (squared distances), unsorted.
struct Collect {
  double radius2;
  std::vector<int>& out;
  void init() {}
  void clear() { out.clear(); }
  std::size_t size() const { return out.size(); }
  bool full() const { return true; }
  bool addPoint(double d2, std::uint32_t index) {
    if (d2 <= radius2) out.push_back(static_cast<int>(index));
    return true;
  }
  double worstDist() const { return std::nextafter(radius2, 1e300); }  // nanoflann keeps d2 < worstDist()
};

}  // namespace

struct CloudKdTree::Impl {
  Dataset data;
  std::unique_ptr<Tree> tree;
};

CloudKdTree::CloudKdTree(std::span<const Eigen::Vector3d> points, int dimensions) : impl_(std::make_unique<Impl>()) {
  if (dimensions != 2 && dimensions != 3) throw std::invalid_argument("CloudKdTree: 2 or 3 dimensions");
  impl_->data.dimensions = dimensions;
  impl_->data.coordinates.reserve(points.size() * static_cast<std::size_t>(dimensions));
  for (const auto& p : points)
    for (int d = 0; d < dimensions; ++d) impl_->data.coordinates.push_back(p[d]);
  impl_->tree = std::make_unique<Tree>(dimensions, impl_->data, nanoflann::KDTreeSingleIndexAdaptorParams(16));
}

CloudKdTree::~CloudKdTree() = default;
CloudKdTree::CloudKdTree(CloudKdTree&&) noexcept = default;
CloudKdTree& CloudKdTree::operator=(CloudKdTree&&) noexcept = default;

std::size_t CloudKdTree::size() const { return impl_->data.kdtree_get_point_count(); }

void CloudKdTree::nearest(const Eigen::Vector3d& p, int k, std::vector<int>& indices, std::vector<double>& squared_distances) const {
  const std::size_t want = std::min<std::size_t>(static_cast<std::size_t>(std::max(k, 0)), size());
  std::vector<std::uint32_t> found(want);
  squared_distances.resize(want);
  const std::size_t n = want == 0 ? 0 : impl_->tree->knnSearch(p.data(), want, found.data(), squared_distances.data());
  indices.assign(found.begin(), found.begin() + static_cast<std::ptrdiff_t>(n));
  squared_distances.resize(n);
}

int CloudKdTree::nearest(const Eigen::Vector3d& p) const {
  if (size() == 0) return -1;
  std::uint32_t index = 0;
  double d2 = 0;
  impl_->tree->knnSearch(p.data(), 1, &index, &d2);
  return static_cast<int>(index);
}

void CloudKdTree::within(const Eigen::Vector3d& p, double r, std::vector<int>& out) const {
  out.clear();
  if (size() == 0 || !(r >= 0)) return;
  Collect collect{r * r, out};
  impl_->tree->findNeighbors(collect, p.data(), nanoflann::SearchParams(32, 0, false));
}

}  // namespace drom::geometry
