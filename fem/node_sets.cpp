#include "fem/node_sets.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <map>

namespace drom::fem {

namespace {
// Local faces in VTK node numbering: corners (counter-clockwise seen from outside) then midsides.
const std::vector<std::vector<int>> kHexFaces = {{0, 3, 2, 1, 11, 10, 9, 8},     {4, 5, 6, 7, 12, 13, 14, 15},
                                                 {0, 1, 5, 4, 8, 17, 12, 16},    {1, 2, 6, 5, 9, 18, 13, 17},
                                                 {2, 3, 7, 6, 10, 19, 14, 18},   {3, 0, 4, 7, 11, 16, 15, 19}};
// Hex27 faces add their centre node.
const std::vector<std::vector<int>> kHex27Faces = {{0, 3, 2, 1, 11, 10, 9, 8, 24},   {4, 5, 6, 7, 12, 13, 14, 15, 25},
                                                   {0, 1, 5, 4, 8, 17, 12, 16, 22},  {1, 2, 6, 5, 9, 18, 13, 17, 21},
                                                   {2, 3, 7, 6, 10, 19, 14, 18, 23}, {3, 0, 4, 7, 11, 16, 15, 19, 20}};
const std::vector<std::vector<int>> kTetFaces = {{0, 2, 1, 6, 5, 4}, {0, 1, 3, 4, 8, 7}, {1, 2, 3, 5, 9, 8}, {0, 3, 2, 7, 9, 6}};

BoundaryFace make_face(const Mesh& mesh, const std::vector<std::vector<int>>& local, int element, int local_face) {
  const int corners = is_hex(mesh.type) ? 4 : 3;
  const auto conn = mesh.element(element);
  BoundaryFace face{element, {}, Eigen::Vector3d::Zero(), Eigen::Vector3d::Zero()};
  for (int l : local[static_cast<std::size_t>(local_face)]) face.nodes.push_back(conn[static_cast<std::size_t>(l)]);
  for (int k = 0; k < corners; ++k) face.centroid += mesh.nodes[static_cast<std::size_t>(face.nodes[static_cast<std::size_t>(k)])];
  face.centroid /= corners;
  const auto& p0 = mesh.nodes[static_cast<std::size_t>(face.nodes[0])];
  const auto& p1 = mesh.nodes[static_cast<std::size_t>(face.nodes[1])];
  const auto& p2 = mesh.nodes[static_cast<std::size_t>(face.nodes[static_cast<std::size_t>(corners - 1)])];
  face.normal = (p1 - p0).cross(p2 - p0).normalized();
  return face;
}

}  // namespace

std::vector<BoundaryFace> boundary_faces(const Mesh& mesh) {
  const auto& local = mesh.type == ElementType::Hex20 ? kHexFaces : mesh.type == ElementType::Hex27 ? kHex27Faces : kTetFaces;
  const int corners = is_hex(mesh.type) ? 4 : 3;
  std::map<std::vector<int>, std::pair<int, int>> seen;  // sorted corners -> (element, local face); element -1 once shared
  for (int e = 0; e < mesh.element_count(); ++e) {
    const auto conn = mesh.element(e);
    for (int f = 0; f < static_cast<int>(local.size()); ++f) {
      std::vector<int> key;
      for (int k = 0; k < corners; ++k) key.push_back(conn[static_cast<std::size_t>(local[static_cast<std::size_t>(f)][static_cast<std::size_t>(k)])]);
      std::sort(key.begin(), key.end());
      auto [it, inserted] = seen.try_emplace(key, e, f);
      if (!inserted) it->second.first = -1;
    }
  }
  std::vector<BoundaryFace> faces;
  for (const auto& [key, owner] : seen) {
    if (owner.first < 0) continue;
    faces.push_back(make_face(mesh, local, owner.first, owner.second));
  }
  return faces;
}

std::vector<BoundaryFace> faces_within(const Mesh& mesh, const std::vector<int>& node_set) {
  const auto& local = mesh.type == ElementType::Hex20 ? kHexFaces : mesh.type == ElementType::Hex27 ? kHex27Faces : kTetFaces;
  const int corners = is_hex(mesh.type) ? 4 : 3;
  std::vector<char> in(static_cast<std::size_t>(mesh.node_count()), 0);
  for (int n : node_set) in[static_cast<std::size_t>(n)] = 1;
  std::map<std::vector<int>, std::pair<int, int>> seen;  // sorted corners -> the first (element, local face)
  for (int e = 0; e < mesh.element_count(); ++e) {
    const auto conn = mesh.element(e);
    for (int f = 0; f < static_cast<int>(local.size()); ++f) {
      bool all = true;
      for (int l : local[static_cast<std::size_t>(f)]) all = all && in[static_cast<std::size_t>(conn[static_cast<std::size_t>(l)])];
      if (!all) continue;
      std::vector<int> key;
      for (int k = 0; k < corners; ++k) key.push_back(conn[static_cast<std::size_t>(local[static_cast<std::size_t>(f)][static_cast<std::size_t>(k)])]);
      std::sort(key.begin(), key.end());
      seen.try_emplace(key, e, f);
    }
  }
  std::vector<BoundaryFace> faces;
  for (const auto& [key, owner] : seen) {
    faces.push_back(make_face(mesh, local, owner.first, owner.second));
  }
  return faces;
}

std::vector<int> nodes_where(const Mesh& mesh, const PointPredicate& predicate) {
  std::vector<int> nodes;
  for (int i = 0; i < mesh.node_count(); ++i)
    if (predicate(mesh.nodes[static_cast<std::size_t>(i)])) nodes.push_back(i);
  return nodes;
}

std::vector<int> face_nodes_where(const Mesh&, const std::vector<BoundaryFace>& faces, const PointPredicate& predicate) {
  std::vector<int> nodes;
  for (const auto& f : faces)
    if (predicate(f.centroid)) nodes.insert(nodes.end(), f.nodes.begin(), f.nodes.end());
  std::sort(nodes.begin(), nodes.end());
  nodes.erase(std::unique(nodes.begin(), nodes.end()), nodes.end());
  return nodes;
}

std::vector<int> node_dofs(const std::vector<int>& nodes, bool x, bool y, bool z) {
  std::vector<int> dofs;
  for (int n : nodes) {
    if (x) dofs.push_back(3 * n);
    if (y) dofs.push_back(3 * n + 1);
    if (z) dofs.push_back(3 * n + 2);
  }
  return dofs;
}

}  // namespace drom::fem
