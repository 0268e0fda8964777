#pragma once
// A volume mesh as removal sees it, whatever its element types and order: isoparametric elements,
// each a map from its reference cell into space given by its nodes and its type's shape functions.
// fem/ implements it for its meshes (fem/mesh_geometry.hpp); levelset/'s removal never needs to know
// the element types.
#include <Eigen/Core>
#include <Eigen/Geometry>

#include <cstddef>

namespace drom::geometry {

// [-1, 1]^3, or the unit tetrahedron with corners (0,0,0), (1,0,0), (0,1,0), (0,0,1).
enum class ReferenceCell { Hexahedron, Tetrahedron };

// How removal judges an element: Centroid, removed or kept whole by its centroid (the seed's
// criterion); VolumeFraction, the fraction of it still there (docs/design.md §2).
enum class RemovalCriterion { Centroid, VolumeFraction };

class ElementGeometry {
 public:
  virtual ~ElementGeometry() = default;
  virtual std::size_t size() const = 0;
  virtual ReferenceCell reference_cell() const = 0;
  // Node coordinates of element e, one column per node.
  virtual Eigen::Matrix3Xd nodes(std::size_t e) const = 0;
  // Shape function values at reference points (the columns of xi): one row per node, one column per
  // point, so that nodes(e) * shape_values(xi) maps the points into element e.
  virtual Eigen::MatrixXd shape_values(const Eigen::Matrix3Xd& xi) const = 0;
  // A box holding the element's nodes (a curved element may bulge past it by its sag).
  virtual const Eigen::AlignedBox3d& bounds(std::size_t e) const = 0;
  // The mean of the corner nodes: the seed's removal criterion tests it.
  virtual const Eigen::Vector3d& centroid(std::size_t e) const = 0;
};

}  // namespace drom::geometry
