#include "offline/part_setup.hpp"

#include "fem/node_sets.hpp"
#include "levelset/gcode.hpp"
#include "levelset/pocket_toolpath.hpp"
#include "fem/structured_mesh.hpp"
#include "fem/tet_mesh.hpp"
#include "support/input_error.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace drom::offline {

fem::ProfileParity parity_of(const case_file::Case& c) {
  if (c.parity == "even") return fem::ProfileParity::Even;
  if (c.parity == "odd") return fem::ProfileParity::Odd;
  return fem::ProfileParity::All;
}

PartModel build_part(const case_file::Case& c) {
  PartModel part;
  if (c.shape == "stl") {
    const fem::Plc plc = fem::read_closed_stl(c.stl);
    Eigen::Vector3d lo = plc.points.front(), hi = lo;
    for (const auto& p : plc.points) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
    part.shape = fem::PartShape::block(lo, hi);
    part.mesh = fem::make_tet_mesh(plc, {c.tet_max_volume, c.tet_radius_edge_ratio, 0});
  } else {
    part.shape = c.shape == "panel" ? fem::PartShape::panel(c.length_x, c.length_y, c.thickness, c.outer_radius)
                                    : fem::PartShape::plate(c.length_x, c.length_y, c.thickness);
    if (c.element != "tet10") {
      part.mesh = fem::make_structured_hex_mesh(part.shape, {c.nx, c.ny, c.nz, c.thickness_grading,
                                                             c.element == "hex27" ? fem::ElementType::Hex27 : fem::ElementType::Hex20});
    } else {
      if (c.shape == "panel") throw InputError(c.origin + ": mesh.element: tet10 meshes of panels need an STL of the panel (part.shape = \"stl\")");
      part.mesh = fem::make_tet_mesh(fem::layered_box_plc({0, 0, 0}, {c.length_x, c.length_y, c.thickness}, {c.thickness - c.pocket_depth}),
                                     {c.tet_max_volume, c.tet_radius_edge_ratio, 0});
    }
  }
  part.material = {c.young_modulus, c.poisson_ratio};
  part.degrees = fem::legendre_degrees(parity_of(c), c.max_degree);
  if (!c.table.empty())
    part.profile = fem::fit_profile(fem::read_profile_table(c.table), part.shape.thickness(), part.degrees);
  else
    part.profile = {part.degrees, c.sigma11, c.sigma22};
  part.truth_profile = part.profile;
  if (c.has_truth) {
    const auto degrees = fem::legendre_degrees(c.truth_parity == "odd" ? fem::ProfileParity::Odd : c.truth_parity == "even" ? fem::ProfileParity::Even : fem::ProfileParity::All,
                                               c.truth_max_degree);
    part.truth_profile = c.truth_table.empty() ? fem::StressProfile{degrees, c.truth_sigma11, c.truth_sigma22}
                                               : fem::fit_profile(fem::read_profile_table(c.truth_table), part.shape.thickness(), degrees);
  }
  for (auto& v : part.truth_profile.sigma11) v *= c.truth_amplitude;
  for (auto& v : part.truth_profile.sigma22) v *= c.truth_amplitude;
  return part;
}

std::vector<int> clamp_dofs(const case_file::Case& c, const PartModel& part) {
  const auto faces = fem::boundary_faces(part.mesh);
  const auto& shape = part.shape;
  const double tol = 1e-6 * std::max({shape.length_u(), shape.length_v(), shape.thickness()});
  std::vector<int> dofs;
  for (std::size_t i = 0; i < c.clamps.size(); ++i) {
    const case_file::ClampSpec& clamp = c.clamps[i];
    const auto nodes = fem::face_nodes_where(part.mesh, faces, [&](const Eigen::Vector3d& x) {
      const Eigen::Vector3d p = shape.to_parametric(x);
      bool on_face = false;
      if (clamp.face == "bottom") on_face = std::abs(p.z()) < tol;
      else if (clamp.face == "top") on_face = std::abs(p.z() - shape.thickness()) < tol;
      else if (clamp.face == "x_min") on_face = std::abs(p.x()) < tol;
      else if (clamp.face == "x_max") on_face = std::abs(p.x() - shape.length_u()) < tol;
      else if (clamp.face == "y_min") on_face = std::abs(p.y()) < tol;
      else if (clamp.face == "y_max") on_face = std::abs(p.y() - shape.length_v()) < tol;
      if (!on_face || !clamp.box) return on_face;
      const auto& b = *clamp.box;
      return p.x() >= b[0] - tol && p.x() <= b[1] + tol && p.y() >= b[2] - tol && p.y() <= b[3] + tol;
    });
    if (nodes.empty())
      throw InputError(c.origin + ": clamps." + std::to_string(i) + ": face \"" + clamp.face +
                       "\" (with its box) contains no element face of the mesh: widen the box or refine the mesh");
    const auto more = fem::node_dofs(nodes, clamp.dofs != "z", clamp.dofs != "z", clamp.dofs != "xy");
    dofs.insert(dofs.end(), more.begin(), more.end());
  }
  std::sort(dofs.begin(), dofs.end());
  dofs.erase(std::unique(dofs.begin(), dofs.end()), dofs.end());
  return dofs;
}


paths::ToolAssembly build_tool(const case_file::Case& c) {
  if (c.tool_kind == "ball") return paths::ToolAssembly::ball(c.tool_radius, c.tool_flute_length);
  if (c.tool_kind == "bull_nose") return paths::ToolAssembly::bull_nose(c.tool_radius, c.tool_corner_radius, c.tool_flute_length);
  return paths::ToolAssembly::flat(c.tool_radius, c.tool_flute_length);
}

levelset::Toolpath build_toolpath(const case_file::Case& c, const PartModel& part) {
  if (!c.gcode.empty()) return levelset::read_gcode(c.gcode.string());
  const paths::ToolAssembly tool = build_tool(c);
  levelset::PocketPathSpec spec;
  spec.strategy = c.path_strategy == "zigzag" ? levelset::PocketStrategy::Zigzag
                  : c.path_strategy == "spiral" ? levelset::PocketStrategy::Spiral
                                                : levelset::PocketStrategy::OneWay;
  spec.stepover = c.scallop_height > 0 ? levelset::stepover_for_scallop(tool, c.scallop_height) : c.stepover;
  spec.feed = c.feed;
  spec.plunge_feed = c.plunge_feed;
  spec.clearance = c.clearance;
  spec.finish_walls = c.finish_walls;
  try {
    return levelset::pocket_toolpath(part.shape, {c.pocket_x, c.pocket_y, c.pocket_length_x, c.pocket_length_y, c.pocket_depth}, tool, spec);
  } catch (const std::invalid_argument& e) {
    throw InputError(c.origin + ": [pocket]/[tool]/[path]: " + e.what());
  }
}

levelset::Workpiece build_workpiece(const case_file::Case& c, const PartModel& part, double voxel_size) {
  if (c.shape == "stl") return levelset::Workpiece::from_surface(geometry::read_closed_stl(c.stl), voxel_size);
  return levelset::Workpiece::from_shape(part.shape);
}

double voxel_size_for(const case_file::Case& c, const PartModel& part) {
  if (c.voxel_size > 0) return c.voxel_size;
  double thinnest = part.shape.thickness();
  for (int e = 0; e < part.mesh.element_count(); ++e) {
    const Eigen::Matrix3Xd X = part.mesh.element_nodes(e);
    const Eigen::Vector3d extent = X.rowwise().maxCoeff() - X.rowwise().minCoeff();
    thinnest = std::min(thinnest, extent.minCoeff());
  }
  return levelset::default_voxel_size(build_tool(c), c.pocket_depth, thinnest);
}

pgd::PgdSettings pgd_settings(const case_file::Case& c) {
  pgd::PgdSettings s;
  const auto& k = c.pgd;
  if (k.residual_tolerance) s.residual_tolerance = *k.residual_tolerance;
  if (k.increment_tolerance) s.increment_tolerance = *k.increment_tolerance;
  if (k.fixed_point_tolerance) s.fixed_point_tolerance = *k.fixed_point_tolerance;
  if (k.max_modes) s.max_modes = *k.max_modes;
  if (k.max_fixed_point_iterations) s.max_fixed_point_iterations = *k.max_fixed_point_iterations;
  if (k.anderson_depth) s.anderson_depth = *k.anderson_depth;
  if (k.max_update_functions) s.max_update_functions = *k.max_update_functions;
  if (k.update_every) s.update_every = *k.update_every;
  if (k.warm_start_truncation) s.warm_start_truncation = *k.warm_start_truncation;
  return s;
}

}  // namespace drom::offline
