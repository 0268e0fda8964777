#include "offline/mesh_output.hpp"

#include "fem/vtk_output.hpp"
#include "offline/part_setup.hpp"
#include "support/summary.hpp"

namespace drom::offline {

nlohmann::json write_mesh(const case_file::Case& c, const std::filesystem::path& out) {
  clear_earlier_run(out, "mesh");
  const PartModel part = build_part(c);
  const auto clamped = clamp_dofs(c, part);
  std::vector<double> clamp_flag(static_cast<std::size_t>(part.mesh.node_count()), 0.0);
  for (int d : clamped) clamp_flag[static_cast<std::size_t>(d / 3)] = 1.0;
  std::vector<double> s(static_cast<std::size_t>(part.mesh.node_count()));
  for (int n = 0; n < part.mesh.node_count(); ++n) s[static_cast<std::size_t>(n)] = part.shape.reduced_thickness(part.mesh.nodes[static_cast<std::size_t>(n)]);
  fem::VtuFields fields;
  fields.point_scalars = {{"clamped", clamp_flag}, {"reduced_thickness", s}};
  fem::write_vtu(out / "mesh.vtu", part.mesh, fields);
  const nlohmann::json summary{{"command", "mesh"},
                               {"case", c.name},
                               {"element", fem::element_name(part.mesh.type)},
                               {"elements", part.mesh.element_count()},
                               {"nodes", part.mesh.node_count()},
                               {"unknowns", part.mesh.dof_count()},
                               {"clamped_dofs", clamped.size()},
                               {"files", {"mesh.vtu"}}};
  write_summary(out, summary);
  return summary;
}

}  // namespace drom::offline
