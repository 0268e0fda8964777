// drom check, drom mesh, drom layer, drom removal: what a case describes, built and inspected
// (case_file/case.hpp, offline/mesh_output.hpp, offline/layer_check.hpp, offline/removal_job.hpp).
#include "apps/commands.hpp"
#include "offline/layer_check.hpp"
#include "offline/mesh_output.hpp"
#include "offline/removal_job.hpp"

#include <cstdio>
#include <iostream>

namespace drom::app {

int check_command(const CommandOptions& options) {
  const case_file::Case c = case_file::load_case(options.case_path, options.overrides);
  std::cout << "# " << c.origin << ": valid case '" << c.name << "'; resolved values follow\n" << c.resolved_toml << "\n";
  return 0;
}

int mesh_command(const CommandOptions& options) {
  const case_file::Case c = case_file::load_case(options.case_path, options.overrides);
  const auto s = offline::write_mesh(c, options.out);
  if (!options.quiet)
    std::printf("%s: %d %s elements, %d unknowns, %zu clamped dofs -> %s\n", c.name.c_str(), s["elements"].get<int>(), s["element"].get<std::string>().c_str(),
                s["unknowns"].get<int>(), s["clamped_dofs"].get<std::size_t>(), (options.out / "mesh.vtu").string().c_str());
  return 0;
}

int layer_command(const CommandOptions& options) {
  const case_file::Case c = case_file::load_case(options.case_path, options.overrides);
  const auto s = offline::run_layer_check(c, options.out, options.quiet);
  if (options.quiet) return 0;
  std::printf("drom layer: %s (%d %s elements, %d unknowns)\n", c.name.c_str(), s["mesh"]["elements"].get<int>(), s["mesh"]["element"].get<std::string>().c_str(),
              s["mesh"]["unknowns"].get<int>());
  std::printf("  intact stock, clamped: max |u|          %.2e mm (equilibrium residual %.1e)\n", s["intact_clamped_max_displacement_mm"].get<double>(),
              s["equilibrium_residual_relative"].get<double>());
  std::printf("  thinned by %.3g mm, clamped: max |w|     %.4f mm\n", c.pocket_depth, s["thinned_clamped_max_vertical_displacement_mm"].get<double>());
  std::printf("  thinned, unclamped (best fit): max |w|  %.4f mm\n", s["thinned_free_max_vertical_displacement_mm"].get<double>());
  if (s.contains("free_plate_curvature_per_mm")) {
    const auto& k = s["free_plate_curvature_per_mm"];
    std::printf("  free plate curvature kx, ky  %.4e, %.4e 1/mm (closed form %.4e, %.4e; error %.3f %%)\n", k["fe"][0].get<double>(), k["fe"][1].get<double>(),
                k["closed_form"][0].get<double>(), k["closed_form"][1].get<double>(), 100 * k["relative_error"].get<double>());
  }
  std::printf("  outputs: %s/layer.pvd (open in ParaView), summary.json; %.1f s\n", options.out.string().c_str(), s["timing_s"]["total"].get<double>());
  return 0;
}

int removal_command(const CommandOptions& options) {
  const case_file::Case c = case_file::load_case(options.case_path, options.overrides);
  const auto s = offline::run_removal(c, options.out, options.quiet);
  if (!options.quiet)
    std::printf("drom removal: %s: %zu stations, removed %.1f mm^3 (level set; OpenVDB measure %.1f), %.1f mm^3 on the mesh; %.1f s -> %s\n", c.name.c_str(),
                s["stations"].get<std::size_t>(), s["removed_volume_mm3"].get<double>(), s["removed_volume_openvdb_measure_mm3"].get<double>(),
                s["mesh_removed_volume_mm3"].get<double>(), s["time_s"].get<double>(), options.out.string().c_str());
  return 0;
}

}  // namespace drom::app
