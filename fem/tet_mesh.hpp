#pragma once
// Quadratic tetrahedral meshes of closed surfaces (geometry/closed_surface.hpp) through TetGen.
#include "fem/mesh.hpp"
#include "geometry/closed_surface.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace drom::fem {

using geometry::layered_box_plc;
using geometry::Plc;
using geometry::read_closed_stl;

struct TetMeshSpec {
  double max_volume = 0;         // mm^3 per tetrahedron; 0 = no limit
  double radius_edge_ratio = 1.4; // TetGen's quality bound (switch q)
  double min_dihedral_deg = 0;    // optional second quality bound (q/ratio/angle)
};

// Tet10 mesh of the PLC through TetGen; midside nodes at straight-edge midpoints.
Mesh make_tet_mesh(const Plc& plc, const TetMeshSpec& spec);

}  // namespace drom::fem
