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

namespace {

// What the sweep gives, station by station.
struct RemovalSweep {
  std::vector<float> activity;                  // stations x elements: the remaining fractions
  std::vector<double> removed, mesh_removed;    // mm3 so far: the level set's, the mesh's
  std::string csv;                              // volumes.csv
  fem::PvdCollection pvd;                       // the frames
};

// What it is run on.
struct RemovalInputs {
  const case_file::Case& c;
  const fem::Mesh& mesh;
  MachiningRun& run;
  const std::vector<double>& volumes;  // per element
  const std::filesystem::path& out;
  bool quiet = false;
  std::chrono::steady_clock::time_point start = {};
};

// The elements still holding material at station k, with their remaining fractions.
void write_removal_frame(const std::filesystem::path& out, const fem::Mesh& mesh, const std::vector<double>& remaining, std::size_t k, double time,
                         fem::PvdCollection& pvd) {
  const std::size_t ne = remaining.size();
  std::vector<char> keep(ne);
  for (std::size_t e = 0; e < ne; ++e) keep[e] = remaining[e] > 0;
  fem::VtuFields fields;
  fields.cell_scalars = {{"remaining_fraction", remaining}};
  char name[64];
  std::snprintf(name, sizeof name, "removal_%05zu.vtu", k);
  fem::write_vtu(out / "frames" / name, mesh, fields, keep);
  pvd.add(time, std::filesystem::path("frames") / name);
}

// One line rewritten in place on a terminal, one line per update in a log.
void print_removal_progress(std::size_t k, std::size_t ns, double seconds, bool interactive) {
  const double rate = static_cast<double>(k + 1) / seconds;
  std::fprintf(stderr, "%s  station %zu/%zu  %.1f stations/s  %.0f s left%s", interactive ? "\r" : "", k + 1, ns, rate,
               static_cast<double>(ns - k - 1) / rate, interactive ? "   " : "\n");
}

RemovalSweep sweep_stations(const RemovalInputs& in) {
  const auto& stations = in.run.stations();
  const std::size_t ns = stations.size(), ne = static_cast<std::size_t>(in.mesh.element_count());
  RemovalSweep sweep;
  sweep.activity.reserve(ns * ne);
  sweep.removed.resize(ns), sweep.mesh_removed.resize(ns);
  std::vector<double> remaining(ne, 1.0);
  const int frames = std::max(1, std::min<int>(in.c.frames, static_cast<int>(ns)));
  std::ostringstream csv;
  csv << "station,time_s,path_length_mm,x,y,z,removed_mm3,station_removed_mm3,mesh_removed_mm3\n";
  const bool interactive = isatty(2) != 0;
  for (std::size_t k = 0; k < ns; ++k) {
    const double added = in.run.advance(remaining);
    double gone = 0;
    for (std::size_t e = 0; e < ne; ++e) {
      sweep.activity.push_back(static_cast<float>(remaining[e]));
      gone += (1 - remaining[e]) * in.volumes[e];
    }
    sweep.removed[k] = in.run.removal().removed_volume();
    sweep.mesh_removed[k] = gone;
    char row[256];
    std::snprintf(row, sizeof row, "%zu,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f\n", k, stations[k].time, stations[k].path_length, stations[k].position.x(),
                  stations[k].position.y(), stations[k].position.z(), sweep.removed[k], added, gone);
    csv << row;
    if (frame_at(k, ns, static_cast<std::size_t>(frames))) write_removal_frame(in.out, in.mesh, remaining, k, stations[k].time, sweep.pvd);
    if (!in.quiet && (k % std::max<std::size_t>(1, ns / 20) == 0 || k + 1 == ns)) print_removal_progress(k, ns, seconds_since(in.start), interactive);
  }
  if (!in.quiet && interactive) std::cerr << "\n";
  sweep.csv = csv.str();
  return sweep;
}

void write_removal_files(const case_file::Case& c, const std::filesystem::path& out, const MachiningRun& run, const RemovalSweep& sweep,
                         const std::vector<double>& volumes) {
  const std::size_t ns = run.stations().size(), ne = volumes.size();
  sweep.pvd.write(out / "removal.pvd");
  write_file_atomically(out / "volumes.csv", sweep.csv);
  write_file_atomically(out / "toolpath.nc", levelset::write_gcode(run.path(), c.name + " toolpath"));
  run.removal().write_surface(out / "removed_surface.vtp");
  Hdf5Writer h5(out / "removal.h5");
  h5.write("activity", sweep.activity, ns, ne);
  write_stations(h5, run.stations());
  h5.write("removed_volume", sweep.removed, ns, 1);
  h5.write("mesh_removed_volume", sweep.mesh_removed, ns, 1);
  h5.write("element_volume", volumes, ne, 1);
  h5.attribute("case", c.resolved_toml);
  h5.attribute("criterion", c.removal_criterion);
  h5.attribute("voxel_size_mm", run.voxel_size());
  h5.commit();
}

nlohmann::json removal_summary(const case_file::Case& c, const MachiningRun& run, const RemovalSweep& sweep, std::size_t elements,
                               std::chrono::steady_clock::time_point start) {
  const std::size_t ns = run.stations().size();
  const auto& removal = run.removal();
  const double measured = removal.measured_volume();
  return {{"command", "removal"},
          {"case", c.name},
          {"stations", ns},
          {"moves", run.path().moves.size()},
          {"path_duration_s", run.timeline().duration()},
          {"elements", elements},
          {"criterion", c.removal_criterion},
          {"voxel_size_mm", run.voxel_size()},
          {"removed_volume_mm3", removal.removed_volume()},
          {"removed_volume_openvdb_measure_mm3", measured},
          {"mesh_removed_volume_mm3", sweep.mesh_removed.back()},
          {"active_voxels", removal.active_voxels()},
          {"level_set_memory_mb", static_cast<double>(removal.memory_bytes()) / 1048576.0},
          {"time_s", seconds_since(start)},
          {"time_per_station_ms", 1000 * seconds_since(start) / static_cast<double>(ns)},
          {"machine", machine_info()},
          {"files", {"removal.h5", "volumes.csv", "removal.pvd", "removed_surface.vtp", "toolpath.nc"}}};
}

}  // namespace

nlohmann::json run_removal(const case_file::Case& c, const std::filesystem::path& out, bool quiet) {
  clear_earlier_run(out, "removal");
  const auto start = std::chrono::steady_clock::now();
  const PartModel part = build_part(c);
  const auto& mesh = part.mesh;
  MachiningRun run(c, part);
  const auto volumes = fem::element_volumes(mesh);
  if (!quiet)
    std::cerr << c.name << ": " << run.path().moves.size() << " moves, " << run.stations().size() << " stations, " << mesh.element_count()
              << " elements, voxel " << run.voxel_size() << " mm\n";
  const RemovalSweep sweep = sweep_stations({.c = c, .mesh = mesh, .run = run, .volumes = volumes, .out = out, .quiet = quiet, .start = start});
  write_removal_files(c, out, run, sweep, volumes);
  const nlohmann::json summary = removal_summary(c, run, sweep, volumes.size(), start);
  write_summary(out, summary);
  return summary;
}

}  // namespace drom::offline
