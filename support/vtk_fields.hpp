#pragma once
// Fields on the points and cells of a grid, written to VTK XML for ParaView (atomically): any grid
// (fem/ writes its meshes with it), surfaces given as nodes and faces, and .pvd time series.
#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

class vtkUnstructuredGrid;

namespace drom {

struct VtuFields {
  std::vector<std::pair<std::string, Eigen::VectorXd>> point_vectors;       // 3 values per point
  std::vector<std::pair<std::string, std::vector<double>>> point_scalars;   // 1 value per point
  std::vector<std::pair<std::string, std::vector<double>>> cell_scalars;    // 1 value per field cell
  std::vector<std::pair<std::string, std::vector<Eigen::Matrix<double, 6, 1>>>> cell_tensors;  // Voigt, written as 3x3
};

// The grid (its points first, `node_count` of them) with the fields; grid cell k carries the cell
// fields' values at kept[k].
void write_vtu_grid(vtkUnstructuredGrid& grid, long long node_count, const VtuFields& fields, const std::vector<int>& kept,
                    const std::filesystem::path& path);

// A surface (3 x n nodes, faces of 3, 4, 6, 8 or 9 nodes in VTK order) with point and cell fields.
void write_surface_vtu(const std::filesystem::path& path, const Eigen::Matrix3Xd& nodes, const std::vector<int>& faces, int nodes_per_face,
                       const VtuFields& fields);

// Polylines (a toolpath, a set of passes) as a .vtp: points (3 x n), each line the indices of its
// points in order; point fields have one value (or 3 for vectors) per point, cell fields one per line.
struct Polylines {
  Eigen::Matrix3Xd points;
  std::vector<std::vector<long long>> lines;
  VtuFields fields;  // point_scalars, point_vectors, cell_scalars (cell_tensors unused)
};
void write_polylines_vtp(const std::filesystem::path& path, const Polylines& polylines);

// Points alone (a point cloud: each point a vertex cell) with point fields, as a .vtp.
void write_points_vtp(const std::filesystem::path& path, const Eigen::Matrix3Xd& points, const VtuFields& fields);

// A .pvd collection: ParaView opens it as one time series.
class PvdCollection {
 public:
  void add(double time, const std::filesystem::path& vtu_relative_path) { entries_.emplace_back(time, vtu_relative_path); }
  void write(const std::filesystem::path& path) const;
  std::size_t size() const { return entries_.size(); }

 private:
  std::vector<std::pair<double, std::filesystem::path>> entries_;
};

}  // namespace drom
