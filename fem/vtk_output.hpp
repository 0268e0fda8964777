#pragma once
// The mesh and its fields to VTK XML files for ParaView (.vtu per state).
#include "fem/element_operators.hpp"
#include "fem/mesh.hpp"
#include "support/vtk_fields.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace drom::fem {

// The fields and the generic writers (surfaces, .pvd series) live in support/vtk_fields.hpp.
using drom::PvdCollection;
using drom::VtuFields;
using drom::write_surface_vtu;

// Writes the elements whose `keep` flag is set (empty: all) with their fields; atomic.
void write_vtu(const std::filesystem::path& path, const Mesh& mesh, const VtuFields& fields, const std::vector<char>& keep = {});

class ElasticProblem;

// The problem's current state: the cells that still hold material, the named displacement fields,
// and the element-average total stress, von Mises stress and activity for profile 0 under the
// first displacement. Call it right after the solve, while the activity is that state's.
void write_solution_vtu(const std::filesystem::path& path, const ElasticProblem& problem,
                        const std::vector<std::pair<std::string, Eigen::VectorXd>>& displacements);

}  // namespace drom::fem
