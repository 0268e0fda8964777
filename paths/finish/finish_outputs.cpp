#include "paths/finish/finish_outputs.hpp"

#include "paths/finish/parallel_planes.hpp"
#include "support/atomic_file.hpp"
#include "support/vtk_fields.hpp"
#include "support/vtk_xml.hpp"

#include <vtkCellArray.h>
#include <vtkCellData.h>
#include <vtkDoubleArray.h>
#include <vtkNew.h>
#include <vtkPoints.h>
#include <vtkPolyData.h>
#include <vtkPolyLine.h>
#include <vtkXMLPolyDataWriter.h>

#include <cmath>
#include <iomanip>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace drom::paths {

namespace {
constexpr double kDeg = 180 / std::numbers::pi;
}

void write_zone_map(const std::filesystem::path& path, const geometry::NurbsSurface& surface, const SurfaceSamples& samples, const Zones& zones) {
  const int nu = samples.cells_u, nv = samples.cells_v;
  Eigen::Matrix3Xd nodes(3, (nu + 1) * (nv + 1));
  for (int i = 0; i <= nu; ++i)
    for (int j = 0; j <= nv; ++j)
      nodes.col(i * (nv + 1) + j) = surface.point(surface.u_min() + (surface.u_max() - surface.u_min()) * i / nu, surface.v_min() + (surface.v_max() - surface.v_min()) * j / nv);
  std::vector<int> faces;
  std::vector<double> zone, cluster, slope, azimuth;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      faces.insert(faces.end(), {i * (nv + 1) + j, (i + 1) * (nv + 1) + j, (i + 1) * (nv + 1) + j + 1, i * (nv + 1) + j + 1});
      const int k = samples.index(i, j), z = zones.zone[static_cast<std::size_t>(k)];
      zone.push_back(z);
      cluster.push_back(z >= 0 ? zones.cluster[static_cast<std::size_t>(z)] : -1);
      slope.push_back(samples.features[static_cast<std::size_t>(k)](2) * kDeg);
      azimuth.push_back(samples.features[static_cast<std::size_t>(k)](3) * kDeg);
    }
  VtuFields fields;
  fields.cell_scalars = {{"zone", zone}, {"cluster", cluster}, {"slope_deg", slope}, {"steepest_azimuth_deg", azimuth}};
  write_surface_vtu(path, nodes, faces, 4, fields);
}

void write_pass_polylines(const std::filesystem::path& path, const FinishingPlan& plan, const Tool& tool) {
  vtkNew<vtkPoints> points;
  points->SetDataTypeToDouble();
  vtkNew<vtkCellArray> lines;
  vtkNew<vtkDoubleArray> zone, pass, kind, spacing, order;
  zone->SetName("zone");
  pass->SetName("pass");
  kind->SetName("kind");  // 0: contact points (CC), 1: tool tips (CL)
  spacing->SetName("plane_step_mm");
  order->SetName("machining_order");
  int sequence = 0;
  for (const auto& z : plan.zones) {
    const Eigen::Vector3d axis = z.setup.axis();
    for (std::size_t k = 0; k < z.passes.size(); ++k) {
      const PlanePass& p = z.passes[k];
      for (int which = 0; which < 2; ++which) {
        vtkNew<vtkPolyLine> line;
        line->GetPointIds()->SetNumberOfIds(static_cast<vtkIdType>(p.cc.size()));
        for (std::size_t i = 0; i < p.cc.size(); ++i) {
          const Eigen::Vector3d q = which == 0 ? p.cc[i] : cutter_location(p.cc[i], p.normals[i], tool, axis);
          line->GetPointIds()->SetId(static_cast<vtkIdType>(i), points->InsertNextPoint(q.x(), q.y(), q.z()));
        }
        lines->InsertNextCell(line);
        zone->InsertNextValue(z.zone);
        pass->InsertNextValue(static_cast<double>(k));
        kind->InsertNextValue(which);
        spacing->InsertNextValue(p.spacing);
        order->InsertNextValue(sequence);
      }
      ++sequence;
    }
  }
  vtkNew<vtkPolyData> poly;
  poly->SetPoints(points);
  poly->SetLines(lines);
  for (auto* a : {zone.GetPointer(), pass.GetPointer(), kind.GetPointer(), spacing.GetPointer(), order.GetPointer()}) poly->GetCellData()->AddArray(a);
  vtkNew<vtkXMLPolyDataWriter> writer;
  writer->SetInputData(poly);
  write_vtk_xml(*writer, path);
}

void write_cl_csv(const std::filesystem::path& path, const FinishingPlan& plan, const Tool& tool) {
  std::ostringstream csv;
  csv << std::setprecision(10);
  csv << "zone,pass,point,tip_x,tip_y,tip_z,axis_i,axis_j,axis_k,cc_x,cc_y,cc_z,machine_x,machine_y,machine_z\n";
  for (const auto& z : plan.zones) {
    const Eigen::Vector3d axis = z.setup.axis();
    for (std::size_t k = 0; k < z.passes.size(); ++k) {
      const PlanePass& p = z.passes[k];
      for (std::size_t i = 0; i < p.cc.size(); ++i) {
        const Eigen::Vector3d tip = cutter_location(p.cc[i], p.normals[i], tool, axis), m = z.setup.to_machine(tip);
        csv << z.zone << ',' << k << ',' << i << ',' << tip.x() << ',' << tip.y() << ',' << tip.z() << ',' << axis.x() << ',' << axis.y() << ',' << axis.z() << ','
            << p.cc[i].x() << ',' << p.cc[i].y() << ',' << p.cc[i].z() << ',' << m.x() << ',' << m.y() << ',' << m.z() << '\n';
      }
    }
  }
  write_file_atomically(path, csv.str());
}

machine::ClProgram cl_program(const FinishingPlan& plan, const Tool& tool, double feed, double clearance, double approach) {
  machine::ClProgram cl;
  cl.origin = "drom finish";
  const auto add = [&](const Eigen::Vector3d& tip, const Eigen::Vector3d& axis, double f, bool rapid) {
    machine::ClPoint p;
    p.pose.tip = tip;
    p.pose.axis = axis;
    p.feed = f;
    p.rapid = rapid;
    cl.points.push_back(p);
  };
  for (const auto& z : plan.zones) {
    const Eigen::Vector3d axis = z.setup.axis();
    for (std::size_t k = 0; k < z.passes.size(); ++k) {
      const PlanePass& p = z.passes[k];
      std::vector<Eigen::Vector3d> tips;
      for (std::size_t i = 0; i < p.cc.size(); ++i) tips.push_back(cutter_location(p.cc[i], p.normals[i], tool, axis));
      if (k == 0 || z.retract_before[k]) {
        if (k > 0) {
          const Eigen::Vector3d& last = cl.points.back().pose.tip;
          add(last + clearance * axis, axis, feed, true);
        }
        add(tips.front() + clearance * axis, axis, feed, true);
        add(tips.front() + approach * axis, axis, feed, true);
        add(tips.front(), axis, feed / 2, false);
      } else {
        add(tips.front(), axis, feed, false);
      }
      for (std::size_t i = 1; i < tips.size(); ++i) add(tips[i], axis, feed, false);
    }
    if (!cl.points.empty()) add(cl.points.back().pose.tip + clearance * axis, axis, feed, true);
  }
  return cl;
}

void write_breakdown_csv(const std::filesystem::path& path, const FinishingPlan& plan) {
  std::ostringstream csv;
  csv << std::setprecision(8);
  csv << "zone,order,azimuth_deg,axis_i,axis_j,axis_k,zeta_deg,passes,links,retracts,pass_time_s,link_time_s,retract_time_s,pass_length_mm,link_length_mm,time_s\n";
  int order = 0;
  for (const auto& z : plan.zones) {
    const Eigen::Vector3d a = z.setup.axis();
    csv << z.zone << ',' << order++ << ',' << z.setup.azimuth * kDeg << ',' << a.x() << ',' << a.y() << ',' << a.z() << ',' << z.setup.zeta * kDeg << ','
        << z.passes.size() << ',' << z.links << ',' << z.retracts << ',' << z.pass_time << ',' << z.link_time << ',' << z.retract_time << ',' << z.pass_length
        << ',' << z.link_length << ',' << z.time() << '\n';
  }
  int links = 0, retracts = 0;
  for (const auto& z : plan.zones) links += z.links, retracts += z.retracts;
  // Moves between zones are retracts too: counted and timed in the retract columns of their row.
  csv << "between_zones,,,,,,,,," << plan.moves << ",,," << plan.move_time << ",,," << plan.move_time << '\n';
  csv << "total,,,,,,," << plan.pass_count() << ',' << links << ',' << retracts + plan.moves << ',' << plan.pass_time() << ',' << plan.link_time() << ','
      << plan.retract_time() + plan.move_time << ',' << plan.pass_length() << ',' << plan.link_length() << ',' << plan.time() << '\n';
  write_file_atomically(path, csv.str());
}

}  // namespace drom::paths
