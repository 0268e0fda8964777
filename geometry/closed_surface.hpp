#pragma once
// Closed triangulated surfaces: STL reading with closedness and orientation checks, and simple
// piecewise-linear complexes. Workpieces given as STL start here; fem/ meshes them with TetGen.
#include <Eigen/Core>

#include <filesystem>
#include <vector>

namespace drom::geometry {

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

}  // namespace drom::geometry
