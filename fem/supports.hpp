#pragma once
// Isostatic (3-2-1) supports and the best-fit rigid alignment a metrology lab applies to a
// free part's measured shape (docs/design.md §3).
#include "fem/mesh.hpp"
#include "geometry/part_shape.hpp"

#include <Eigen/Core>

#include <vector>

namespace drom::fem {

// Six dofs that hold the part against rigid motion without loading it: the live node nearest each
// of three bottom corners of the part (p = (0,0,0), (lu,0,0), (0,lv,0)) is held in xyz, yz and z.
std::vector<int> isostatic_dofs(const Mesh& mesh, const PartShape& shape, const std::vector<char>& live_nodes);

// Removes from u the small rigid motion t + w x (x - c) that best fits it (least squares) over the
// given nodes; returns the fitted (t, w) as a 6-vector.
Eigen::Matrix<double, 6, 1> remove_rigid_motion(const Mesh& mesh, const std::vector<int>& nodes, Eigen::VectorXd& u);

}  // namespace drom::fem
