#include "fem/mesh_geometry.hpp"

#include "fem/shape_functions.hpp"

namespace drom::fem {

MeshGeometry::MeshGeometry(const Mesh& mesh) : mesh_(mesh) {
  const auto n = static_cast<std::size_t>(mesh.element_count());
  bounds_.resize(n);
  centroid_.resize(n);
  for (int e = 0; e < mesh.element_count(); ++e) {
    const Eigen::Matrix3Xd X = mesh.element_nodes(e);
    bounds_[static_cast<std::size_t>(e)] = Eigen::AlignedBox3d(X.rowwise().minCoeff(), X.rowwise().maxCoeff());
    centroid_[static_cast<std::size_t>(e)] = mesh.centroid(e);
  }
}

geometry::ReferenceCell MeshGeometry::reference_cell() const {
  return is_hex(mesh_.type) ? geometry::ReferenceCell::Hexahedron : geometry::ReferenceCell::Tetrahedron;
}

Eigen::Matrix3Xd MeshGeometry::nodes(std::size_t e) const { return mesh_.element_nodes(static_cast<int>(e)); }

Eigen::MatrixXd MeshGeometry::shape_values(const Eigen::Matrix3Xd& xi) const {
  Eigen::MatrixXd values(nodes_per_element(mesh_.type), xi.cols());
  Eigen::VectorXd N;
  Eigen::MatrixX3d dN;
  for (Eigen::Index p = 0; p < xi.cols(); ++p) {
    shape_functions(mesh_.type, xi.col(p), N, dN);
    values.col(p) = N;
  }
  return values;
}

}  // namespace drom::fem
