#include "support/vtk_fields.hpp"

#include "support/atomic_file.hpp"
#include "support/vtk_xml.hpp"

#include <vtkCellData.h>
#include <vtkCellType.h>
#include <vtkDoubleArray.h>
#include <vtkIdList.h>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkPoints.h>
#include <vtkCellArray.h>
#include <vtkPolyData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLPolyDataWriter.h>
#include <vtkXMLUnstructuredGridWriter.h>

#include <sstream>
#include <stdexcept>

namespace drom {

namespace {

// Polylines (or, with `as_vertices`, one vertex cell per point) and their fields, as a .vtp.
void write_vtp(const std::filesystem::path& path, const Polylines& p, bool as_vertices) {
  const auto n = static_cast<vtkIdType>(p.points.cols());
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  points->SetNumberOfPoints(n);
  for (vtkIdType i = 0; i < n; ++i) points->SetPoint(i, p.points(0, i), p.points(1, i), p.points(2, i));
  vtkNew<vtkCellArray> lines;
  for (const auto& line : p.lines) {
    lines->InsertNextCell(static_cast<int>(line.size()));
    for (long long id : line) {
      if (id < 0 || id >= n) throw std::invalid_argument("write_polylines_vtp: a line refers to point " + std::to_string(id) + " of " + std::to_string(n));
      lines->InsertCellPoint(static_cast<vtkIdType>(id));
    }
  }
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(points);
  if (as_vertices) {
    vtkNew<vtkCellArray> vertices;
    for (vtkIdType i = 0; i < n; ++i) {
      vertices->InsertNextCell(1);
      vertices->InsertCellPoint(i);
    }
    poly->SetVerts(vertices);
  } else {
    poly->SetLines(lines);
  }
  for (const auto& [name, values] : p.fields.point_vectors) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(name.c_str());
    a->SetNumberOfComponents(3);
    a->SetNumberOfTuples(n);
    for (vtkIdType i = 0; i < n; ++i) a->SetTuple3(i, values[3 * i], values[3 * i + 1], values[3 * i + 2]);
    poly->GetPointData()->AddArray(a);
  }
  for (const auto& [name, values] : p.fields.point_scalars) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(name.c_str());
    a->SetNumberOfTuples(n);
    for (vtkIdType i = 0; i < n; ++i) a->SetValue(i, values[static_cast<std::size_t>(i)]);
    poly->GetPointData()->AddArray(a);
  }
  for (const auto& [name, values] : p.fields.cell_scalars) {
    if (values.size() != p.lines.size()) throw std::invalid_argument("write_polylines_vtp: cell field " + name + " has " + std::to_string(values.size()) + " values for " + std::to_string(p.lines.size()) + " lines");
    vtkNew<vtkDoubleArray> a;
    a->SetName(name.c_str());
    a->SetNumberOfTuples(static_cast<vtkIdType>(values.size()));
    for (std::size_t k = 0; k < values.size(); ++k) a->SetValue(static_cast<vtkIdType>(k), values[k]);
    poly->GetCellData()->AddArray(a);
  }
  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetInputData(poly);
  write_vtk_xml(*writer, path);
}

}  // namespace

void write_polylines_vtp(const std::filesystem::path& path, const Polylines& polylines) { write_vtp(path, polylines, false); }

void write_points_vtp(const std::filesystem::path& path, const Eigen::Matrix3Xd& points, const VtuFields& fields) {
  Polylines p;
  p.points = points;
  p.fields = fields;
  if (!p.fields.cell_scalars.empty()) throw std::invalid_argument("write_points_vtp: points carry point fields only");
  write_vtp(path, p, true);
}

// The fields on a grid whose points are the mesh's nodes and whose cells are the `kept` elements.
void write_vtu_grid(vtkUnstructuredGrid& grid, long long node_count, const VtuFields& fields, const std::vector<int>& kept, const std::filesystem::path& path) {
  for (const auto& [name, values] : fields.point_vectors) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(name.c_str());
    a->SetNumberOfComponents(3);
    a->SetNumberOfTuples(static_cast<vtkIdType>(node_count));
    for (vtkIdType i = 0; i < static_cast<vtkIdType>(node_count); ++i) a->SetTuple3(i, values[3 * i], values[3 * i + 1], values[3 * i + 2]);
    grid.GetPointData()->AddArray(a);
  }
  for (const auto& [name, values] : fields.point_scalars) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(name.c_str());
    a->SetNumberOfTuples(static_cast<vtkIdType>(node_count));
    for (vtkIdType i = 0; i < static_cast<vtkIdType>(node_count); ++i) a->SetValue(i, values[static_cast<std::size_t>(i)]);
    grid.GetPointData()->AddArray(a);
  }
  for (const auto& [name, values] : fields.cell_scalars) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(name.c_str());
    a->SetNumberOfTuples(static_cast<vtkIdType>(kept.size()));
    for (std::size_t k = 0; k < kept.size(); ++k) a->SetValue(static_cast<vtkIdType>(k), values[static_cast<std::size_t>(kept[k])]);
    grid.GetCellData()->AddArray(a);
  }
  for (const auto& [name, values] : fields.cell_tensors) {
    vtkNew<vtkDoubleArray> a;
    a->SetName(name.c_str());
    a->SetNumberOfComponents(9);
    a->SetNumberOfTuples(static_cast<vtkIdType>(kept.size()));
    for (std::size_t k = 0; k < kept.size(); ++k) {
      const auto& s = values[static_cast<std::size_t>(kept[k])];
      const double t[9] = {s[0], s[5], s[4], s[5], s[1], s[3], s[4], s[3], s[2]};
      a->SetTuple(static_cast<vtkIdType>(k), t);
    }
    grid.GetCellData()->AddArray(a);
  }
  vtkNew<vtkXMLUnstructuredGridWriter> writer;
  writer->SetInputData(&grid);
  write_vtk_xml(*writer, path);
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
  write_vtu_grid(*grid, nodes.cols(), fields, kept, path);
}

void PvdCollection::write(const std::filesystem::path& path) const {
  std::ostringstream xml;
  xml << "<?xml version=\"1.0\"?>\n<VTKFile type=\"Collection\" version=\"0.1\">\n  <Collection>\n";
  for (const auto& [time, file] : entries_)
    xml << "    <DataSet timestep=\"" << time << "\" part=\"0\" file=\"" << file.generic_string() << "\"/>\n";
  xml << "  </Collection>\n</VTKFile>\n";
  write_file_atomically(path, xml.str());
}

}  // namespace drom
