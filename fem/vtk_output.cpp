#include "fem/vtk_output.hpp"

#include "fem/elastic_problem.hpp"

#include "support/vtk_fields.hpp"

#include <vtkCellArray.h>
#include <vtkCellType.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>

#include <stdexcept>

namespace drom::fem {

void write_vtu(const std::filesystem::path& path, const Mesh& mesh, const VtuFields& fields, const std::vector<char>& keep) {
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(mesh.node_count());
  for (int i = 0; i < mesh.node_count(); ++i) {
    const auto& p = mesh.nodes[static_cast<std::size_t>(i)];
    points->SetPoint(i, p.x(), p.y(), p.z());
  }
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(points);
  const int cell_type = mesh.type == ElementType::Hex20   ? VTK_QUADRATIC_HEXAHEDRON
                        : mesh.type == ElementType::Hex27 ? VTK_TRIQUADRATIC_HEXAHEDRON
                                                          : VTK_QUADRATIC_TETRA;
  std::vector<int> kept;
  for (int e = 0; e < mesh.element_count(); ++e) {
    if (!keep.empty() && !keep[static_cast<std::size_t>(e)]) continue;
    kept.push_back(e);
    vtkNew<vtkIdList> ids;
    for (int n : mesh.element(e)) ids->InsertNextId(n);
    grid->InsertNextCell(cell_type, ids);
  }
  write_vtu_grid(*grid, mesh.node_count(), fields, kept, path);
}

void write_solution_vtu(const std::filesystem::path& path, const ElasticProblem& problem,
                        const std::vector<std::pair<std::string, Eigen::VectorXd>>& displacements) {
  const auto stresses = problem.element_stresses(0, displacements.front().second);
  std::vector<double> vm(stresses.size());
  for (std::size_t e = 0; e < stresses.size(); ++e) vm[e] = von_mises(stresses[e]);
  std::vector<char> keep(problem.activity().size());
  for (std::size_t e = 0; e < keep.size(); ++e) keep[e] = problem.activity()[e] > 0;
  VtuFields fields;
  fields.point_vectors = displacements;
  fields.cell_scalars = {{"von_mises", vm}, {"activity", problem.activity()}};
  fields.cell_tensors = {{"stress", stresses}};
  write_vtu(path, problem.mesh(), fields, keep);
}

}  // namespace drom::fem
