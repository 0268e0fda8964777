#pragma once
// The plane/out-of-plane tensor discretization of docs/design.md §4: structured quadratic Quad9 elements
// on the part's parametric plane (u, v) times quadratic Line3 elements through the thickness t.
// The 3D space it spans is exactly the Hex27 mesh fem::make_structured_hex_mesh builds for the same
// (nu, nv, nt, grading), with the same node and element numbering, so the two solvers can be compared
// node by node and the PGD field written with fem's VTK output.
#include "fem/mesh.hpp"
#include "geometry/part_shape.hpp"

#include <array>
#include <vector>

namespace drom::pgd {

using geometry::PartShape;

struct TensorGrid {
  PartShape shape;
  int nu = 1, nv = 1, nt = 1;
  std::vector<double> levels;  // nt + 1 element boundaries through the thickness, from the bottom face

  static TensorGrid make(const PartShape& shape, int nu, int nv, int nt, double thickness_grading = 1.0);

  int lattice_u() const { return 2 * nu + 1; }
  int lattice_v() const { return 2 * nv + 1; }
  int plane_nodes() const { return lattice_u() * lattice_v(); }
  int thickness_nodes() const { return 2 * nt + 1; }
  int plane_elements() const { return nu * nv; }
  int node_count() const { return plane_nodes() * thickness_nodes(); }
  double element_size_u() const { return shape.length_u() / nu; }
  double element_size_v() const { return shape.length_v() / nv; }
  // Parametric coordinates of lattice points.
  double u(int i) const { return shape.length_u() * i / (lattice_u() - 1); }
  double v(int j) const { return shape.length_v() * j / (lattice_v() - 1); }
  double t(int k) const;
  Eigen::Vector2d plane_point(int a) const { return {u(a % lattice_u()), v(a / lattice_u())}; }
  // In-plane element e = ej * nu + ei: its 9 nodes in tensor order (local a + 3 b, a along u).
  std::array<int, 9> plane_element_nodes(int e) const;
  // Node and element numbering of the matching Hex27 mesh.
  int node(int plane_node, int thickness_node) const { return thickness_node * plane_nodes() + plane_node; }
  int element(int plane_element, int thickness_element) const { return thickness_element * plane_elements() + plane_element; }
  bool curved() const { return shape.kind() == PartShape::Kind::Panel; }
  // Radius of the thickness coordinate t on a panel (inner face at t = 0).
  double radius(double t) const { return shape.outer_radius() - shape.thickness() + t; }
  double smallest_element_size() const;
  // The Hex27 mesh of the same space (for removal, VTK output and the 3D FE comparison).
  fem::Mesh hex27_mesh() const;
  double grading = 1.0;  // bottom / top element thickness
};

}  // namespace drom::pgd
