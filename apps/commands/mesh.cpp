// drom mesh / drom check: build and inspect what a case describes, without solving.
#include "apps/case_setup.hpp"
#include "apps/commands.hpp"
#include "apps/summary.hpp"
#include "fem/vtk_output.hpp"

#include <iostream>

namespace drom::app {

int check_command(const CommandOptions& options) {
  const Case c = load_case(options.case_path, options.overrides);
  std::cout << "# " << c.origin << ": valid case '" << c.name << "'; resolved values follow\n" << c.resolved_toml << "\n";
  return 0;
}

int mesh_command(const CommandOptions& options) {
  const Case c = load_case(options.case_path, options.overrides);
  const PartModel part = build_part(c);
  const auto clamped = clamp_dofs(c, part);
  std::vector<double> clamp_flag(static_cast<std::size_t>(part.mesh.node_count()), 0.0);
  for (int d : clamped) clamp_flag[static_cast<std::size_t>(d / 3)] = 1.0;
  std::vector<double> s(static_cast<std::size_t>(part.mesh.node_count()));
  for (int n = 0; n < part.mesh.node_count(); ++n) s[static_cast<std::size_t>(n)] = part.shape.reduced_thickness(part.mesh.nodes[static_cast<std::size_t>(n)]);
  fem::VtuFields fields;
  fields.point_scalars = {{"clamped", clamp_flag}, {"reduced_thickness", s}};
  fem::write_vtu(options.out / "mesh.vtu", part.mesh, fields);
  write_summary(options.out, {{"command", "mesh"},
                              {"case", c.name},
                              {"element", fem::element_name(part.mesh.type)},
                              {"elements", part.mesh.element_count()},
                              {"nodes", part.mesh.node_count()},
                              {"unknowns", part.mesh.dof_count()},
                              {"clamped_dofs", clamped.size()},
                              {"files", {"mesh.vtu"}}});
  if (!options.quiet)
    std::cout << c.name << ": " << part.mesh.element_count() << " " << fem::element_name(part.mesh.type) << " elements, " << part.mesh.dof_count()
              << " unknowns, " << clamped.size() << " clamped dofs -> " << (options.out / "mesh.vtu").string() << "\n";
  return 0;
}

}  // namespace drom::app
