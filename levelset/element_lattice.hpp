#pragma once
// The share of a volume element where a function is negative, integrated on a lattice of its
// reference cell: every lattice cell split into tetrahedra (Kuhn's triangulation), the function
// sampled at the lattice points and taken as linear within each tetrahedron, whose negative share is
// then exact (levelset/cut_fraction.hpp). A plane is integrated exactly whatever the spacing, and so
// is any surface whose kinks lie on lattice lines; curved surfaces converge at second order.
#include "geometry/element_geometry.hpp"

#include <Eigen/Core>

#include <array>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <vector>

namespace drom::levelset {

class ElementLattices {
 public:
  ElementLattices();
  ~ElementLattices();

  // A function known two ways: a cheap estimate, and its exact value. The exact value is sampled at
  // the lattice points where the estimate lies within `trust` of zero; the estimate serves elsewhere.
  struct Field {
    std::function<double(const Eigen::Vector3d&)> estimate, exact;
    double trust = 0;
  };

  // Share of element e's volume where the field is negative, on a lattice no coarser than `spacing`
  // along each of the element's directions (capped at 256 cells per direction, 128 per tetrahedron
  // edge).
  double negative_share(const geometry::ElementGeometry& elements, std::size_t e, double spacing, const Field& field) const;

 private:
  struct Lattice;
  std::shared_ptr<const Lattice> lattice(const geometry::ElementGeometry& elements, int node_count, const std::array<int, 3>& cells) const;
  // Shape functions at the probe points (hexahedra: {-1, 0, 1}^3; tetrahedra: the Tet10 nodes),
  // which tell an element's extents and whether its map is affine.
  const Eigen::MatrixXd& probe_shape(const geometry::ElementGeometry& elements, int node_count) const;

  mutable std::mutex mutex_;
  mutable std::map<std::array<int, 5>, std::shared_ptr<const Lattice>> lattices_;  // cell, node count, cells per direction
  mutable std::map<std::array<int, 2>, Eigen::MatrixXd> probe_shapes_;
};

}  // namespace drom::levelset
