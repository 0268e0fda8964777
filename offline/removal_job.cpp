// drom removal: the material each tool station takes away, on the case's mesh (issue 3).
#include "offline/part_setup.hpp"
#include "offline/machining_run.hpp"
#include "support/summary.hpp"
#include "fem/vtk_output.hpp"
#include "levelset/gcode.hpp"
#include "support/atomic_file.hpp"
#include "support/hdf5_writer.hpp"
#include "support/input_error.hpp"
#include "support/resources.hpp"

#include <chrono>
#include <cstdio>
#include <iostream>
#include <sstream>
#include <unistd.h>

namespace drom::offline {

nlohmann::json run_removal(const cases::Case& c, const std::filesystem::path& out, bool quiet) {
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return seconds_since(start); };
  const PartModel part = build_part(c);
  const auto& mesh = part.mesh;
  MachiningRun run(c, part);
  const auto& path = run.path();
  const auto& timeline = run.timeline();
  const auto& stations = run.stations();
  const double voxel = run.voxel_size();
  const auto volumes = fem::element_volumes(mesh);
  if (!quiet)
    std::cerr << c.name << ": " << path.moves.size() << " moves, " << stations.size() << " stations, " << mesh.element_count() << " elements, voxel "
              << voxel << " mm\n";

  const std::size_t ns = stations.size(), ne = static_cast<std::size_t>(mesh.element_count());
  std::vector<float> activity;
  activity.reserve(ns * ne);
  std::vector<double> removed(ns), mesh_removed(ns);
  std::vector<double> remaining(ne, 1.0);
  const int frames = std::max(1, std::min<int>(c.frames, static_cast<int>(ns)));
  fem::PvdCollection pvd;
  std::ostringstream csv;
  csv << "station,time_s,path_length_mm,x,y,z,removed_mm3,station_removed_mm3,mesh_removed_mm3\n";
  const bool interactive = isatty(2) != 0;
  for (std::size_t k = 0; k < ns; ++k) {
    const double added = run.advance(remaining);
    double gone = 0;
    for (std::size_t e = 0; e < ne; ++e) {
      activity.push_back(static_cast<float>(remaining[e]));
      gone += (1 - remaining[e]) * volumes[e];
    }
    removed[k] = run.removal().removed_volume();
    mesh_removed[k] = gone;
    char row[256];
    std::snprintf(row, sizeof row, "%zu,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f\n", k, stations[k].time, stations[k].path_length, stations[k].position.x(),
                  stations[k].position.y(), stations[k].position.z(), removed[k], added, gone);
    csv << row;
    if (frame_at(k, ns, static_cast<std::size_t>(frames))) {
      std::vector<char> keep(ne);
      for (std::size_t e = 0; e < ne; ++e) keep[e] = remaining[e] > 0;
      fem::VtuFields fields;
      fields.cell_scalars = {{"remaining_fraction", remaining}};
      char name[64];
      std::snprintf(name, sizeof name, "removal_%05zu.vtu", k);
      fem::write_vtu(out / "frames" / name, mesh, fields, keep);
      pvd.add(stations[k].time, std::filesystem::path("frames") / name);
    }
    if (!quiet && (k % std::max<std::size_t>(1, ns / 20) == 0 || k + 1 == ns)) {
      const double rate = static_cast<double>(k + 1) / elapsed();
      // One line rewritten in place on a terminal, one line per update in a log.
      std::fprintf(stderr, "%s  station %zu/%zu  %.1f stations/s  %.0f s left%s", interactive ? "\r" : "", k + 1, ns, rate,
                   static_cast<double>(ns - k - 1) / rate, interactive ? "   " : "\n");
    }
  }
  if (!quiet && interactive) std::cerr << "\n";

  pvd.write(out / "removal.pvd");
  write_file_atomically(out / "volumes.csv", csv.str());
  write_file_atomically(out / "toolpath.nc", levelset::write_gcode(path, c.name + " toolpath"));
  run.removal().write_surface(out / "removed_surface.vtp");
  {
    Hdf5Writer h5(out / "removal.h5");
    h5.write("activity", activity, ns, ne);
    write_stations(h5, stations);
    h5.write("removed_volume", removed, ns, 1);
    h5.write("mesh_removed_volume", mesh_removed, ns, 1);
    h5.write("element_volume", volumes, ne, 1);
    h5.attribute("case", c.resolved_toml);
    h5.attribute("criterion", c.removal_criterion);
    h5.attribute("voxel_size_mm", voxel);
    h5.commit();
  }
  const auto& removal = run.removal();
  const double measured = removal.measured_volume();
  const nlohmann::json summary{{"command", "removal"},
                              {"case", c.name},
                              {"stations", ns},
                              {"moves", path.moves.size()},
                              {"path_duration_s", timeline.duration()},
                              {"elements", ne},
                              {"criterion", c.removal_criterion},
                              {"voxel_size_mm", voxel},
                              {"removed_volume_mm3", removal.removed_volume()},
                              {"removed_volume_openvdb_measure_mm3", measured},
                              {"mesh_removed_volume_mm3", mesh_removed.back()},
                              {"active_voxels", removal.active_voxels()},
                              {"level_set_memory_mb", static_cast<double>(removal.memory_bytes()) / 1048576.0},
                              {"time_s", elapsed()},
                              {"time_per_station_ms", 1000 * elapsed() / static_cast<double>(ns)},
                              {"machine", machine_info()},
                              {"files", {"removal.h5", "volumes.csv", "removal.pvd", "removed_surface.vtp", "toolpath.nc"}}};
  write_summary(out, summary);
  return summary;
}

}  // namespace drom::offline
