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

// A .pvd collection: ParaView opens it as one time series.
class PvdCollection {
 public:
  void add(double time, const std::filesystem::path& vtu_relative_path) { entries_.emplace_back(time, vtu_relative_path); }
  void write(const std::filesystem::path& path) const;

 private:
  std::vector<std::pair<double, std::filesystem::path>> entries_;
};

}  // namespace drom::fem
