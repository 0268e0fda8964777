#pragma once
// A volume mesh of quadratic elements. Node ordering inside an element follows VTK's
// (VTK_QUADRATIC_HEXAHEDRON, VTK_TRIQUADRATIC_HEXAHEDRON, VTK_QUADRATIC_TETRA) so meshes go to ParaView unchanged.
#include "geometry/part_shape.hpp"

#include <Eigen/Core>

#include <span>
#include <vector>

namespace drom::fem {

// The stock's geometry is described upstream, where material removal is computed.
using geometry::PartShape;

enum class ElementType { Hex20, Hex27, Tet10 };
// Hexahedra of either kind (serendipity Hex20, or the tensor-product Lagrange Hex27).
inline bool is_hex(ElementType type) { return type != ElementType::Tet10; }

int nodes_per_element(ElementType type);
const char* element_name(ElementType type);

struct Mesh {
  ElementType type = ElementType::Hex20;
  std::vector<Eigen::Vector3d> nodes;
  std::vector<int> connectivity;  // nodes_per_element(type) entries per element

  int node_count() const { return static_cast<int>(nodes.size()); }
  int element_count() const { return static_cast<int>(connectivity.size()) / nodes_per_element(type); }
  int dof_count() const { return 3 * node_count(); }

  std::span<const int> element(int e) const {
    const int n = nodes_per_element(type);
    return {connectivity.data() + static_cast<std::size_t>(e) * n, static_cast<std::size_t>(n)};
  }
  // Coordinates of an element's nodes as columns.
  Eigen::Matrix3Xd element_nodes(int e) const;
  // Centroid of the corner nodes (the seed's removal criterion uses it).
  Eigen::Vector3d centroid(int e) const;
};

// Exact volume of each element (by quadrature; exact for straight-edged elements, converged otherwise).
std::vector<double> element_volumes(const Mesh& mesh);

}  // namespace drom::fem
