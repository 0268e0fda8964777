#pragma once
// Structured 20-node hexahedral meshes of plates and cylindrical panels (any PartShape),
// optionally graded through the thickness.
#include "fem/mesh.hpp"
#include "geometry/part_shape.hpp"

#include <vector>

namespace drom::fem {

struct StructuredMeshSpec {
  int nu = 10, nv = 10, nt = 4;   // elements along u, v and through the thickness
  // Ratio (bottom element thickness) / (top element thickness); 1 is uniform, > 1 refines near the
  // machined top face.
  double thickness_grading = 1.0;
  // Hex20, or Hex27: the tensor product of the in-plane Quad9 and the through-thickness Line3 that
  // the PGD solver (pgd/) discretizes, so both solve on the same space.
  ElementType element = ElementType::Hex20;
};

// Element boundaries through the thickness (nt + 1 values from 0 to thickness).
std::vector<double> thickness_levels(double thickness, int nt, double grading);

// Hex20 or Hex27 mesh of the stock; midside nodes sit on the true (curved) geometry. Node numbering
// runs over the lattice of corner and midside positions, u fastest, then v, then t; Hex27 keeps every
// lattice point, so its node (i, j, k) is (k * (2 nv + 1) + j) * (2 nu + 1) + i.
Mesh make_structured_hex_mesh(const PartShape& shape, const StructuredMeshSpec& spec);

}  // namespace drom::fem
