#pragma once
// Quadratic tetrahedral meshes of closed surfaces: STL input, closedness check, TetGen.
#include "fem/mesh.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace drom::fem {

// A piecewise-linear complex: points and planar polygonal facets (TetGen's input).
struct Plc {
  std::vector<Eigen::Vector3d> points;
  std::vector<std::vector<int>> facets;
};

// Reads an ASCII or binary STL, welds coincident vertices and checks that the surface is closed
// and consistently oriented (every edge shared by exactly two triangles, in opposite directions).
// Throws InputError naming the file and the offending facet or edge.
Plc read_closed_stl(const std::filesystem::path& path);

// Box [min, max] split into layers at the given z levels (strictly inside); the internal facets make
// the tetrahedra conform to each level, so layer removal is exact on tets too.
Plc layered_box_plc(const Eigen::Vector3d& min_corner, const Eigen::Vector3d& max_corner, std::vector<double> z_levels);

struct TetMeshSpec {
  double max_volume = 0;         // mm^3 per tetrahedron; 0 = no limit
  double radius_edge_ratio = 1.4; // TetGen's quality bound (switch q)
  double min_dihedral_deg = 0;    // optional second quality bound (q/ratio/angle)
};

// Tet10 mesh of the PLC through TetGen; midside nodes at straight-edge midpoints.
Mesh make_tet_mesh(const Plc& plc, const TetMeshSpec& spec);

}  // namespace drom::fem
