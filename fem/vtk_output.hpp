#pragma once
// Fields on the mesh to VTK XML files for ParaView: .vtu per state, .pvd for a sequence.
#include "fem/element_operators.hpp"
#include "fem/mesh.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace drom::fem {

struct VtuFields {
  std::vector<std::pair<std::string, Eigen::VectorXd>> point_vectors;       // 3 values per node
  std::vector<std::pair<std::string, std::vector<double>>> point_scalars;   // 1 value per node
  std::vector<std::pair<std::string, std::vector<double>>> cell_scalars;    // 1 value per element
  std::vector<std::pair<std::string, std::vector<Vector6d>>> cell_tensors;  // Voigt, written as 3x3
};

// Writes the elements whose `keep` flag is set (empty: all) with their fields; atomic.
void write_vtu(const std::filesystem::path& path, const Mesh& mesh, const VtuFields& fields, const std::vector<char>& keep = {});

// A surface (3 x n nodes, faces of 3, 4, 6, 8 or 9 nodes in VTK order) with point and cell fields;
// atomic. For the target surface, the final part's surface and predicted shapes.
void write_surface_vtu(const std::filesystem::path& path, const Eigen::Matrix3Xd& nodes, const std::vector<int>& faces, int nodes_per_face,
                       const VtuFields& fields);

class ElasticProblem;

// The problem's current state: the cells that still hold material, the named displacement fields,
// and the element-average total stress, von Mises stress and activity for profile 0 under the
// first displacement. Call it right after the solve, while the activity is that state's.
void write_solution_vtu(const std::filesystem::path& path, const ElasticProblem& problem,
                        const std::vector<std::pair<std::string, Eigen::VectorXd>>& displacements);

// A .pvd collection: ParaView opens it as one time series.
class PvdCollection {
 public:
  void add(double time, const std::filesystem::path& vtu_relative_path) { entries_.emplace_back(time, vtu_relative_path); }
  void write(const std::filesystem::path& path) const;
  std::size_t size() const { return entries_.size(); }

 private:
  std::vector<std::pair<double, std::filesystem::path>> entries_;
};

}  // namespace drom::fem
