#pragma once
// A fem::Mesh as removal sees it (geometry::ElementGeometry): its elements as maps from their reference cells.
#include "fem/mesh.hpp"
#include "geometry/element_geometry.hpp"

#include <vector>

namespace drom::fem {

class MeshGeometry final : public geometry::ElementGeometry {
 public:
  // Keeps a reference to `mesh`, which must outlive it.
  explicit MeshGeometry(const Mesh& mesh);
  std::size_t size() const override { return centroid_.size(); }
  geometry::ReferenceCell reference_cell() const override;
  Eigen::Matrix3Xd nodes(std::size_t e) const override;
  Eigen::MatrixXd shape_values(const Eigen::Matrix3Xd& xi) const override;
  const Eigen::AlignedBox3d& bounds(std::size_t e) const override { return bounds_[e]; }
  const Eigen::Vector3d& centroid(std::size_t e) const override { return centroid_[e]; }

 private:
  const Mesh& mesh_;
  std::vector<Eigen::AlignedBox3d> bounds_;
  std::vector<Eigen::Vector3d> centroid_;
};

}  // namespace drom::fem
