#pragma once
// The target machined surface (docs/design.md §5): the mesh nodes on the pocket floor, t = e - depth,
// inside the pocket's footprint. It is a material surface: these nodes move with the part.
#include "fem/mesh.hpp"

#include <vector>

namespace drom::fem {

struct PocketFootprint {
  double u_min = 0, u_max = 0, v_min = 0, v_max = 0, floor_t = 0;
};

// Nodes on the floor inside the footprint, sorted by (v, u). Throws std::invalid_argument when the
// floor is not a layer of nodes (the mesh must put an element face at the pocket's depth).
std::vector<int> target_surface_nodes(const Mesh& mesh, const PartShape& shape, const PocketFootprint& pocket);

}  // namespace drom::fem
