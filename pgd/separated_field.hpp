#pragma once
// A displacement field in separated form (docs/design.md §4, eq. D.7): each component i of the local
// frame (e1, e2, e3 = along u, along v, thickness normal) is sum_q X_q^i(u, v) Z_q^i(t), with X on the
// in-plane nodes and Z on the thickness nodes of a TensorGrid.
#include "pgd/tensor_grid.hpp"

#include <Eigen/Core>

#include <array>
#include <filesystem>

namespace drom::pgd {

// One full-size 3D array per component: plane_nodes x thickness_nodes (a residual or a load).
using ComponentTensors = std::array<Eigen::MatrixXd, 3>;

ComponentTensors zero_tensors(const TensorGrid& grid);
double norm(const ComponentTensors& r);

struct SeparatedField {
  std::array<Eigen::MatrixXd, 3> X;  // plane_nodes x terms
  std::array<Eigen::MatrixXd, 3> Z;  // thickness_nodes x terms

  static SeparatedField empty(const TensorGrid& grid);
  int terms(int component) const { return static_cast<int>(X[static_cast<std::size_t>(component)].cols()); }
  int max_terms() const;
  std::size_t stored_values() const;
  // Appends the product x (X) z to one component.
  void append(int component, const Eigen::VectorXd& x, const Eigen::VectorXd& z);
  void append(const SeparatedField& other, double scale = 1.0);
  // The component as a plane_nodes x thickness_nodes array.
  Eigen::MatrixXd component(int i) const;
  ComponentTensors tensors() const;
  // Values at the 3D nodes of the matching Hex27 mesh (3 * node + component), in the local frame or
  // rotated to Cartesian x, y, z (the two differ on panels only).
  Eigen::VectorXd local_nodal(const TensorGrid& grid) const;
  Eigen::VectorXd cartesian_nodal(const TensorGrid& grid) const;
  // Value of one Cartesian component at one 3D lattice node, without rebuilding the field.
  double cartesian_at(const TensorGrid& grid, int plane_node, int thickness_node, int axis) const;
  // Re-expresses each component with orthogonal factors and drops terms whose singular value is below
  // relative_tolerance times the largest: the same field (to that tolerance) in the fewest terms.
  void compress(double relative_tolerance);
};

// Modes as HDF5 (datasets X_u, Z_u, X_v, ..., grid attributes), written atomically.
void write_modes_hdf5(const std::filesystem::path& path, const TensorGrid& grid, const SeparatedField& field);

}  // namespace drom::pgd
