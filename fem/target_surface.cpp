#include "fem/target_surface.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace drom::fem {

std::vector<int> target_surface_nodes(const Mesh& mesh, const PartShape& shape, const PocketFootprint& pocket) {
  const double tol = 1e-6 * std::max({shape.length_u(), shape.length_v(), shape.thickness()});
  std::vector<std::pair<Eigen::Vector3d, int>> found;
  for (int n = 0; n < mesh.node_count(); ++n) {
    const Eigen::Vector3d p = shape.to_parametric(mesh.nodes[static_cast<std::size_t>(n)]);
    if (std::abs(p.z() - pocket.floor_t) > tol) continue;
    if (p.x() < pocket.u_min - tol || p.x() > pocket.u_max + tol || p.y() < pocket.v_min - tol || p.y() > pocket.v_max + tol) continue;
    found.emplace_back(p, n);
  }
  if (found.size() < 4)
    throw std::invalid_argument("no layer of mesh nodes at the pocket floor (t = " + std::to_string(pocket.floor_t) +
                                " mm): choose mesh.nz (and grading) so an element face falls at the pocket depth");
  std::sort(found.begin(), found.end(), [&](const auto& a, const auto& b) {
    if (std::abs(a.first.y() - b.first.y()) > tol) return a.first.y() < b.first.y();
    return a.first.x() < b.first.x();
  });
  std::vector<int> nodes;
  for (const auto& f : found) nodes.push_back(f.second);
  return nodes;
}

}  // namespace drom::fem
