#include "offline/calculix_export.hpp"

#include "fem/elastic_problem.hpp"
#include "fem/supports.hpp"
#include "offline/machining_run.hpp"
#include "offline/part_setup.hpp"
#include "support/atomic_file.hpp"
#include "support/input_error.hpp"
#include "support/resources.hpp"
#include "support/summary.hpp"

#include <chrono>
#include <cstdio>
#include <stdexcept>
#include <string>

namespace drom::offline {

CalculixExport export_calculix_station(const case_file::Case& c, JobKind kind, std::size_t station, const std::filesystem::path& out) {
  clear_earlier_run(out, kind == JobKind::Truth ? "truth --export-ccx" : "offline --export-ccx");
  const PartModel part = build_part(c);
  if (part.mesh.type != fem::ElementType::Hex20)
    throw InputError(c.origin + ": --export-ccx: the case's mesh is made of " + fem::element_name(part.mesh.type) +
                     " elements; the CalculiX deck holds Hex20 (C3D20) only (mesh.element = \"hex20\" on a plate or panel)");
  const auto clamped = clamp_dofs(c, part);
  MachiningRun run(c, part);
  const std::size_t ns = run.stations().size();
  if (station >= ns)
    throw InputError(c.origin + ": --export-ccx " + std::to_string(station) + ": the case has stations 0.." + std::to_string(ns - 1));
  std::vector<double> remaining(static_cast<std::size_t>(part.mesh.element_count()), 1.0);
  for (std::size_t k = 0; k <= station; ++k) run.advance(remaining);

  CalculixExport result;
  result.station = station;
  result.stations = ns;
  const fem::StressProfile& profile = kind == JobKind::Truth ? part.truth_profile : part.profile;
  fem::ElasticProblem problem(part.mesh, part.shape, part.material, {profile});
  problem.equilibrate(fem::isostatic_dofs(part.mesh, part.shape, std::vector<char>(static_cast<std::size_t>(part.mesh.node_count()), 1)));
  problem.set_activity(remaining);
  problem.set_fixed_dofs(clamped);
  const auto t = std::chrono::steady_clock::now();
  problem.assemble_and_factorize();
  result.drom_displacement = problem.solve().col(0);
  result.drom_solve_seconds = seconds_since(t);

  const std::string stem = "station_" + std::to_string(station);
  result.deck = out / (stem + ".inp");
  result.drom_csv = out / (stem + "_drom.csv");
  const std::string heading = "drom " + std::string(kind == JobKind::Truth ? "truth" : "offline") + " " + c.name + ": station " + std::to_string(station) +
                              " of " + std::to_string(ns) + " (" + (kind == JobKind::Truth ? "[truth]" : "[stress]") + " profile)";
  result.deck_stats = fem::write_calculix_deck(result.deck, problem, part.material, 0, heading);

  std::string csv = "node,ux,uy,uz\n";
  char row[128];
  for (int n = 0; n < part.mesh.node_count(); ++n) {
    const Eigen::Vector3d u = result.drom_displacement.segment<3>(3 * n);
    const int length = std::snprintf(row, sizeof row, "%d,%.17g,%.17g,%.17g\n", n + 1, u.x(), u.y(), u.z());
    csv.append(row, static_cast<std::size_t>(length));
  }
  write_file_atomically(result.drom_csv, csv);

  const auto& d = result.deck_stats;
  result.summary = {{"command", kind == JobKind::Truth ? "truth --export-ccx" : "offline --export-ccx"},
                    {"case", c.name},
                    {"station", station},
                    {"stations", ns},
                    {"profile", kind == JobKind::Truth ? "truth" : "stress"},
                    {"nodes", d.nodes},
                    {"elements", d.elements},
                    {"unknowns", part.mesh.dof_count()},
                    {"removed_elements", d.removed},
                    {"partial_elements", d.partial},
                    {"fixed_dofs", d.fixed_dofs},
                    {"deck_mb", d.megabytes},
                    {"drom_solve_s", result.drom_solve_seconds},
                    {"drom_max_displacement_mm", result.drom_displacement.cwiseAbs().maxCoeff()},
                    {"run", "ccx -i " + stem},
                    {"files", {result.deck.filename().string(), result.drom_csv.filename().string()}},
                    {"machine", machine_info()}};
  write_summary(out, result.summary);
  return result;
}

}  // namespace drom::offline
