#include "fem/vtk_output.hpp"

#include "fem/elastic_problem.hpp"

#include "support/atomic_file.hpp"
#include "support/vtk_xml.hpp"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDoubleArray.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <sstream>
#include <stdexcept>

namespace drom::fem {

namespace {

// The fields on a grid whose points are the mesh's nodes and whose cells are the `kept` elements.
void write_grid(vtkUnstructuredGrid* grid, vtkIdType node_count, const VtuFields& fields, const std::vector<int>& kept, const std::filesystem::path& path) {
  for (const auto& [name, values] : fields.point_vectors) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(name.c_str());
    a->SetNumberOfComponents(3);
    a->SetNumberOfTuples(node_count);
    for (vtkIdType i = 0; i < node_count; ++i) a->SetTuple3(i, values[3 * i], values[3 * i + 1], values[3 * i + 2]);
    grid->GetPointData()->AddArray(a);
  }
  for (const auto& [name, values] : fields.point_scalars) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(name.c_str());
    a->SetNumberOfTuples(node_count);
    for (vtkIdType i = 0; i < node_count; ++i) a->SetValue(i, values[static_cast<std::size_t>(i)]);
    grid->GetPointData()->AddArray(a);
  }
  for (const auto& [name, values] : fields.cell_scalars) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(name.c_str());
    a->SetNumberOfTuples(static_cast<vtkIdType>(kept.size()));
    for (std::size_t k = 0; k < kept.size(); ++k) a->SetValue(static_cast<vtkIdType>(k), values[static_cast<std::size_t>(kept[k])]);
    grid->GetCellData()->AddArray(a);
  }
  for (const auto& [name, values] : fields.cell_tensors) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(name.c_str());
    a->SetNumberOfComponents(9);
    a->SetNumberOfTuples(static_cast<vtkIdType>(kept.size()));
    for (std::size_t k = 0; k < kept.size(); ++k) {
      const Vector6d& s = values[static_cast<std::size_t>(kept[k])];
      const double t[9] = {s[0], s[5], s[4], s[5], s[1], s[3], s[4], s[3], s[2]};
      a->SetTuple(static_cast<vtkIdType>(k), t);
    }
    grid->GetCellData()->AddArray(a);
  }
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->SetInputData(grid);
  write_vtk_xml(*writer, path);
}

}  // namespace

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
  write_grid(grid, mesh.node_count(), fields, kept, path);
}

void write_surface_vtu(const std::filesystem::path& path, const Eigen::Matrix3Xd& nodes, const std::vector<int>& faces, int nodes_per_face,
                       const VtuFields& fields) {
  int cell_type = 0;
  switch (nodes_per_face) {
    case 3: cell_type = VTK_TRIANGLE; break;
    case 4: cell_type = VTK_QUAD; break;
    case 6: cell_type = VTK_QUADRATIC_TRIANGLE; break;
    case 8: cell_type = VTK_QUADRATIC_QUAD; break;
    case 9: cell_type = VTK_BIQUADRATIC_QUAD; break;
    default: throw std::invalid_argument("write_surface_vtu: faces of " + std::to_string(nodes_per_face) + " nodes");
  }
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(nodes.cols());
  for (Eigen::Index i = 0; i < nodes.cols(); ++i) points->SetPoint(i, nodes(0, i), nodes(1, i), nodes(2, i));
  vtkNew<vtkUnstructuredGrid> grid;
  grid->SetPoints(points);
  std::vector<int> kept;
  for (std::size_t f = 0; f * static_cast<std::size_t>(nodes_per_face) < faces.size(); ++f) {
    kept.push_back(static_cast<int>(f));
    vtkNew<vtkIdList> ids;
    for (int k = 0; k < nodes_per_face; ++k) ids->InsertNextId(faces[f * static_cast<std::size_t>(nodes_per_face) + static_cast<std::size_t>(k)]);
    grid->InsertNextCell(cell_type, ids);
  }
  write_grid(grid, nodes.cols(), fields, kept, path);
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

void PvdCollection::write(const std::filesystem::path& path) const {
  std::ostringstream xml;
  xml << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n";
  for (const auto& [time, file] : entries_)
    xml << "    <DataSet timestep=\"" << time << "\" part=\"0\" file=\"" << file.generic_string() << "\"/>\n";
  xml << "  </Collection>\n</VTKFile>\n";
  write_file_atomically(path, xml.str());
}

}  // namespace drom::fem
