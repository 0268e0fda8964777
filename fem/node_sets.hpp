#pragma once
// Node and boundary-face sets chosen by geometric predicates (clamps, surfaces, supports).
#include "fem/mesh.hpp"

#include <Eigen/Core>

#include <functional>
#include <vector>

namespace drom::fem {

using PointPredicate = std::function<bool(const Eigen::Vector3d&)>;

struct BoundaryFace {
  int element;
  std::vector<int> nodes;   // corner nodes first, then midside nodes
  Eigen::Vector3d centroid; // of the corner nodes
  Eigen::Vector3d normal;   // outward, unit (from the corner nodes)
};

// Faces that belong to exactly one element.
std::vector<BoundaryFace> boundary_faces(const Mesh& mesh);
// Every element face (inner ones too, each once) whose nodes all lie in node_set: a surface of the
// mesh given by its nodes, such as the target machined surface inside the stock. The normal is the
// first owning element's outward one.
std::vector<BoundaryFace> faces_within(const Mesh& mesh, const std::vector<int>& node_set);

std::vector<int> nodes_where(const Mesh& mesh, const PointPredicate& predicate);
// Nodes of the boundary faces whose centroid satisfies the predicate (sorted, unique).
std::vector<int> face_nodes_where(const Mesh& mesh, const std::vector<BoundaryFace>& faces, const PointPredicate& predicate);
// The three dofs of each node.
std::vector<int> node_dofs(const std::vector<int>& nodes, bool x = true, bool y = true, bool z = true);

}  // namespace drom::fem
