#pragma once
// A drom case: the part, its mesh, material, residual stress, pocket and clamps, read from TOML
// (docs/case-files.md lists every key, its unit and its range).
#include <array>
#include <filesystem>
#include <optional>
#include <cstdint>
#include <string>
#include <vector>

namespace drom::case_file {

struct ClampSpec {
  std::string face;                   // bottom, top, x_min, x_max, y_min, y_max (parametric faces)
  std::optional<std::array<double, 4>> box;  // [u_min, u_max, v_min, v_max] restricting the face, mm
  std::string dofs = "xyz";
};

// The [solver] keys of the PGD that the file gives; the others keep the solver's own defaults
// (pgd::PgdSettings), so the case never repeats them.
struct PgdKeys {
  std::optional<double> residual_tolerance, increment_tolerance, fixed_point_tolerance, warm_start_truncation;
  std::optional<int> max_modes, max_fixed_point_iterations, anderson_depth, max_update_functions, update_every;
};

struct Case {
  std::string name, description;
  std::string origin;         // file path or "<embedded default case>"
  std::string resolved_toml;  // the case after --set overrides, verbatim for outputs

  // [part]
  std::string shape;  // plate, panel, stl
  double length_x = 0, length_y = 0, thickness = 0, outer_radius = 0;
  std::filesystem::path stl;

  // [material]
  double young_modulus = 0, poisson_ratio = 0;

  // [solver]
  std::string solver = "fe";    // fe (3D finite elements), pgd (plane x thickness separated, hex27)
  PgdKeys pgd;                  // the PGD's tolerances and caps the file sets
  double pgd_penalty = 1e8;     // clamp penalty, relative to 2G x smallest element size
  double pgd_indicator_tolerance = 1e-6;  // truncation of the material indicator's SVD
  // FE: a full factorization per this many stations; the others refactorize only the dofs the tool
  // changes (docs/benchmarks.md). 1: a full factorization at every station; 0 ("auto", the default):
  // chosen per job from the removal history (offline/station_schedule.hpp).
  int stations_per_factorization = 0;
  // FE: a refactorized station whose relative residual max_p ||K u_p - f_p|| / ||f_p|| exceeds this is
  // solved again on a full factorization.
  double residual_bound = 1e-8;

  // [mesh]
  std::string element;  // hex20, hex27, tet10
  int nx = 0, ny = 0, nz = 0;
  double thickness_grading = 1;
  double tet_max_volume = 0, tet_radius_edge_ratio = 1.4;

  // [stress]
  std::string parity;  // even, odd, all
  int max_degree = 0;
  std::vector<double> sigma11, sigma22;  // MPa, one per degree of the basis
  std::filesystem::path table;           // optional measured profile, fitted to the basis

  // [pocket]
  double pocket_x = 0, pocket_y = 0, pocket_length_x = 0, pocket_length_y = 0, pocket_depth = 0;

  // [tool]
  std::string tool_kind;  // flat, ball, bull_nose
  double tool_radius = 0, tool_corner_radius = 0, tool_flute_length = 0;

  // [path]
  std::string path_strategy;  // one_way, zigzag, spiral
  double stepover = 0;        // mm (given, or from scallop_height)
  double scallop_height = 0;  // mm, 0 when the stepover is given
  double feed = 0, plunge_feed = 0, clearance = 0;
  bool finish_walls = true;
  std::filesystem::path gcode;  // optional program to read instead of generating one
  std::string stations;         // spacing, waypoints
  double station_spacing = 0;   // mm of cutting travel

  // [removal]
  std::string removal_criterion;  // centroid, volume_fraction
  double voxel_size = 0;          // mm; 0 = chosen from the tool and the mesh
  int frames = 0;                 // VTK frames of the remaining part written by drom removal

  std::vector<ClampSpec> clamps;

  // [truth]: the real part of drom run, whose profile need not be a combination of the basis.
  // Absent: the [stress] profile.
  bool has_truth = false;
  std::string truth_parity;
  int truth_max_degree = 0;
  std::vector<double> truth_sigma11, truth_sigma22;
  std::filesystem::path truth_table;
  double truth_amplitude = 1;  // multiplies the truth's stresses (and so its displacements)

  // [sensor]: the laser sheet (docs/design.md §7).
  std::array<double, 3> sensor_offset{50, 0, 80};
  double sensor_angle = 90, sensor_length = 80, sensor_range = 200, sensor_period = 0.1, sensor_noise = 0.05;
  int sensor_points = 800;
  std::array<double, 3> sensor_offset_error{0, 0, 0};
  double sensor_angle_error = 0;
  std::uint32_t sensor_seed = 2015;

  // [sync]: how the machine moves and how the predictor knows where the tool is.
  double desync = 0, feed_override = 1;
  std::string sync_machine = "vmc_3axis";  // the machine whose real feed the loop's tool follows (file or shipped name); empty: the programmed feed
  std::string sync_reckoning = "machine";  // between edges the synchronizer reckons with that machine's motion, or at the "programmed" feed

  // [control]: the predictor and the offsets it commands.
  bool correct = true;
  double refresh_rate = 10;          // Hz
  double max_offset_rate = 1;        // mm/s
  double max_offset = 0;             // mm: bound on the commanded offset; 0: from the model's prior (online/predictor.hpp)
  double learning_tolerance = 0.01;  // mm
  int learning_window = 5;
  double reading_range = 1;          // mm
  double prior_scale = 1;
  bool use_stock_top = true;         // fit the laser's readings of the unmachined top too (absolute w)
  double model_tolerance = 1e-3;     // mm: the POD bound drom run reduces the offline database to

  // [replan]: drom run --replan, the finish re-planned on the final part (loop/replanned_finish.hpp,
  // loop/final_scan.hpp).
  double replan_tool_diameter = 10;   // mm, a ball
  double replan_scallop = 0.002;      // mm
  double replan_tolerance = 0.002;    // mm: the chord tolerance along the passes
  double replan_step = 1;             // mm along the passes
  double replan_sample_spacing = 0;   // mm between the final surface's sampled points; 0: sqrt(8 R tolerance)
  double replan_scan_step = 0.5;      // mm between the unclamped part's laser profiles

  // [program]: the corrected program's header and moves between cuts, the keys drom finish, copy
  // and orient read (machine/program_keys.hpp; docs/case-files.md, "[program]").
  int program_tool_number = 1;       // T and H
  double program_spindle_speed = 0;  // rev/min; 0: 300 m/min on the tool's diameter
  std::string program_spindle = "cw";    // cw (M3) or ccw (M4)
  std::string program_coolant = "off";   // off, flood (M8) or mist (M7)
  double program_clearance = 10;     // mm above the path's highest point: the plane rapids cross

  // [run]: what drom run does with the case.
  std::string run_scale = "quick";               // quick: apply run.quick first; seed: the case as written
  std::vector<std::string> run_quick;            // "key=value" overrides for a run of a few minutes
  double path_tolerance = 1e-3, shape_tolerance = 0.02;  // mm: the headline targets
  int shape_pass = 3;                                    // the final-shape target applies from the end of this pass
  std::vector<int> shape_vtk_passes;             // passes whose final-shape predictions go to VTK
};

// Reads a case from a file, or the embedded default (flat plate) when `path` is empty, applies the
// "key=value" overrides, validates everything. Throws InputError.
Case load_case(const std::optional<std::filesystem::path>& path, const std::vector<std::string>& overrides);
// The same from TOML text (a case stored in a database or model); `origin` names it in errors and
// anchors relative file paths.
Case case_from_text(const std::string& text, const std::string& origin, const std::vector<std::string>& overrides = {});

// The text of cases/flat_plate.toml, compiled in.
const char* embedded_default_case();

}  // namespace drom::case_file
