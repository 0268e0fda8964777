#include "case_file/case.hpp"

#include "support/toml_reader.hpp"
#include "case_file/default_case.hpp"
#include "support/input_error.hpp"

#include <cmath>

namespace drom::case_file {

const char* embedded_default_case() { return kDefaultCaseToml; }

namespace {

std::filesystem::path relative_to(const std::string& origin, const std::string& file) {
  std::filesystem::path p(file);
  if (p.is_absolute() || origin.empty() || origin.front() == '<') return p;
  return std::filesystem::path(origin).parent_path() / p;
}

void read_part(TomlReader& r, Case& c) {
  c.shape = r.choice("part.shape", {"plate", "panel", "stl"});
  if (c.shape == "stl") {
    c.stl = relative_to(r.origin(), r.text("part.stl"));
    return;
  }
  c.length_x = r.real("part.length_x", Range::positive());
  c.length_y = r.real("part.length_y", Range::positive());
  c.thickness = r.real("part.thickness", Range::positive());
  if (c.shape == "panel") {
    c.outer_radius = r.real("part.outer_radius", Range::positive());
    if (c.outer_radius <= c.thickness) r.fail("part.outer_radius", "must exceed part.thickness");
    if (c.length_x / c.outer_radius > 3.0) r.fail("part.length_x", "the panel's arc spans more than 3 rad: expected a shallow panel");
  }
}

void read_solver(TomlReader& r, Case& c) {
  c.solver = r.choice("solver.kind", {"fe", "pgd"}, "fe");
  if (c.solver != "pgd") {
    // "auto" (0): chosen per job from the removal history (offline/station_schedule.hpp).
    if (r.is_text("solver.stations_per_factorization")) {
      r.choice("solver.stations_per_factorization", {"auto"});
      c.stations_per_factorization = 0;
    } else {
      c.stations_per_factorization = static_cast<int>(r.integer("solver.stations_per_factorization", 1, 10000, c.stations_per_factorization));
    }
    c.residual_bound = r.real("solver.residual_bound", Range::open(0, 1), c.residual_bound);
    for (const char* key : {"solver.residual_tolerance", "solver.increment_tolerance", "solver.fixed_point_tolerance", "solver.max_modes", "solver.max_fixed_point_iterations",
                            "solver.anderson_depth", "solver.max_update_functions", "solver.update_every", "solver.warm_start_truncation", "solver.indicator_tolerance", "solver.penalty"})
      if (r.has(key)) r.fail(key, "is a setting of the PGD solver: it needs solver.kind = \"pgd\"");
    return;
  }
  for (const char* key : {"solver.stations_per_factorization", "solver.residual_bound"})
    if (r.has(key)) r.fail(key, "is a setting of the FE solver: it needs solver.kind = \"fe\"");
  if (c.shape == "stl") r.fail("solver.kind", "pgd separates the plane from the thickness: it needs a plate or a panel, not an STL part");
  auto& s = c.pgd;
  auto real = [&](const char* key, Range range) { return r.has(key) ? std::optional<double>(r.real(key, range)) : std::nullopt; };
  auto integer = [&](const char* key, long long lo, long long hi) {
    return r.has(key) ? std::optional<int>(static_cast<int>(r.integer(key, lo, hi))) : std::nullopt;
  };
  s.residual_tolerance = real("solver.residual_tolerance", Range::open(0, 1));
  s.increment_tolerance = real("solver.increment_tolerance", Range::open(0, 1));
  s.fixed_point_tolerance = real("solver.fixed_point_tolerance", Range::open(0, 1));
  s.max_modes = integer("solver.max_modes", 1, 1000);
  s.max_fixed_point_iterations = integer("solver.max_fixed_point_iterations", 1, 1000);
  s.anderson_depth = integer("solver.anderson_depth", 0, 20);
  s.max_update_functions = integer("solver.max_update_functions", 0, 300);
  s.update_every = integer("solver.update_every", 1, 100);
  s.warm_start_truncation = real("solver.warm_start_truncation", Range::open(0, 1));
  c.pgd_indicator_tolerance = r.real("solver.indicator_tolerance", Range::open(0, 1), c.pgd_indicator_tolerance);
  c.pgd_penalty = r.real("solver.penalty", Range::closed(1e3, 1e14), c.pgd_penalty);
}

void read_mesh(TomlReader& r, Case& c) {
  const char* fallback = c.shape == "stl" ? "tet10" : c.solver == "pgd" ? "hex27" : "hex20";
  c.element = r.choice("mesh.element", {"hex20", "hex27", "tet10"}, fallback);
  if (c.solver == "pgd" && c.element != "hex27")
    r.fail("mesh.element", "solver.kind = \"pgd\" solves on the tensor product of Quad9 and Line3 elements: expected \"hex27\"");
  if (c.element != "tet10") {
    if (c.shape == "stl") r.fail("mesh.element", c.element + " meshes are structured: STL parts need \"tet10\"");
    c.nx = static_cast<int>(r.integer("mesh.nx", 1, 2000));
    c.ny = static_cast<int>(r.integer("mesh.ny", 1, 2000));
    c.nz = static_cast<int>(r.integer("mesh.nz", 1, 200));
    c.thickness_grading = r.real("mesh.thickness_grading", Range::closed(0.05, 20), 1.0);
  } else {
    c.tet_max_volume = r.real("mesh.tet_max_volume", Range::positive());
    c.tet_radius_edge_ratio = r.real("mesh.tet_radius_edge_ratio", Range::closed(1.1, 10), 1.4);
  }
}

int profile_count(const std::string& parity, int max_degree) {
  int count = 0;
  for (int j = 2; j <= max_degree; ++j)
    if (parity == "all" || (parity == "even") == (j % 2 == 0)) ++count;
  return count;
}

// `section`.sigma11 and .sigma22: one coefficient (MPa) per degree of the parity's basis.
void read_coefficients(TomlReader& r, const std::string& section, const std::string& parity, int max_degree, std::vector<double>& sigma11,
                       std::vector<double>& sigma22) {
  const int count = profile_count(parity, max_degree);
  const Range mpa = Range::closed(-2000, 2000);
  sigma11 = r.reals(section + ".sigma11", mpa);
  sigma22 = r.reals(section + ".sigma22", mpa);
  for (const auto* v : {&sigma11, &sigma22}) {
    const std::string key = section + (v == &sigma11 ? ".sigma11" : ".sigma22");
    if (static_cast<int>(v->size()) != count)
      r.fail(key, "has " + std::to_string(v->size()) + " coefficients; the " + parity + " basis up to degree " + std::to_string(max_degree) + " has " +
                      std::to_string(count));
  }
}

void read_stress(TomlReader& r, Case& c) {
  c.parity = r.choice("stress.parity", {"even", "odd", "all"});
  c.max_degree = static_cast<int>(r.integer("stress.max_degree", c.parity == "odd" ? 3 : 2, 20));
  if (r.has("stress.table")) {
    c.table = relative_to(r.origin(), r.text("stress.table"));
    if (r.has("stress.sigma11") || r.has("stress.sigma22")) r.fail("stress.table", "give either a table or sigma11/sigma22 coefficients, not both");
    return;
  }
  read_coefficients(r, "stress", c.parity, c.max_degree, c.sigma11, c.sigma22);
}

void read_pocket(TomlReader& r, Case& c) {
  c.pocket_x = r.real("pocket.x_min", Range::non_negative());
  c.pocket_y = r.real("pocket.y_min", Range::non_negative());
  c.pocket_length_x = r.real("pocket.length_x", Range::positive());
  c.pocket_length_y = r.real("pocket.length_y", Range::positive());
  c.pocket_depth = r.real("pocket.depth", Range::positive());
  if (c.shape != "stl") {
    if (c.pocket_x + c.pocket_length_x > c.length_x) r.fail("pocket.length_x", "the pocket extends past the part (x_min + length_x > part.length_x)");
    if (c.pocket_y + c.pocket_length_y > c.length_y) r.fail("pocket.length_y", "the pocket extends past the part (y_min + length_y > part.length_y)");
    if (c.pocket_depth >= c.thickness) r.fail("pocket.depth", "must be less than part.thickness");
  }
}

void read_tool(TomlReader& r, Case& c) {
  c.tool_kind = r.choice("tool.kind", {"flat", "ball", "bull_nose"});
  c.tool_radius = r.real("tool.radius", Range::positive());
  if (c.tool_kind == "bull_nose") {
    c.tool_corner_radius = r.real("tool.corner_radius", Range::positive());
    if (c.tool_corner_radius >= c.tool_radius) r.fail("tool.corner_radius", "must be smaller than tool.radius (equal is a ball end mill)");
  } else {
    c.tool_corner_radius = c.tool_kind == "ball" ? c.tool_radius : 0.0;
  }
  c.tool_flute_length = r.real("tool.flute_length", Range::positive(), 3 * c.tool_radius);
  if (c.tool_flute_length <= c.pocket_depth) r.fail("tool.flute_length", "must exceed pocket.depth");
}

void read_path(TomlReader& r, Case& c) {
  c.path_strategy = r.choice("path.strategy", {"one_way", "zigzag", "spiral"}, "one_way");
  if (r.has("path.gcode")) {
    c.gcode = relative_to(r.origin(), r.text("path.gcode"));
    for (const char* generated : {"path.stepover", "path.scallop_height", "path.strategy", "path.finish_walls"})
      if (r.has(generated)) r.fail(generated, "describes a generated toolpath, but path.gcode gives the program: remove one of them");
  }
  if (r.has("path.scallop_height")) {
    if (r.has("path.stepover")) r.fail("path.scallop_height", "give either path.stepover or path.scallop_height, not both");
    if (c.tool_kind == "flat") r.fail("path.scallop_height", "a flat end mill leaves no scallop on a flat floor: set path.stepover");
    c.scallop_height = r.real("path.scallop_height", Range::open_closed(0, c.tool_corner_radius));
  } else if (c.gcode.empty()) {
    c.stepover = r.real("path.stepover", Range::open_closed(0, 2 * c.tool_radius));
  }
  c.feed = r.real("path.feed", Range::positive(), 10.0);
  c.plunge_feed = r.real("path.plunge_feed", Range::positive(), c.feed / 5);
  c.clearance = r.real("path.clearance", Range::positive(), 5.0);
  c.finish_walls = r.boolean("path.finish_walls", true);
  c.stations = r.choice("path.stations", {"spacing", "waypoints"}, "spacing");
  if (c.stations == "spacing") c.station_spacing = r.real("path.station_spacing", Range::positive());
}

void read_clamps(TomlReader& r, Case& c) {
  const std::size_t n = r.table_count("clamps");
  if (n == 0) r.fail("clamps", "missing; expected at least one [[clamps]] table holding the part");
  for (std::size_t i = 0; i < n; ++i) {
    const std::string k = "clamps." + std::to_string(i) + ".";
    ClampSpec clamp;
    clamp.face = r.choice(k + "face", {"bottom", "top", "x_min", "x_max", "y_min", "y_max"});
    if (r.has(k + "box")) {
      const auto b = r.reals(k + "box", Range::non_negative());
      if (b.size() != 4 || b[0] >= b[1] || b[2] >= b[3]) r.fail(k + "box", "expected [u_min, u_max, v_min, v_max] with min < max");
      clamp.box = std::array<double, 4>{b[0], b[1], b[2], b[3]};
    }
    clamp.dofs = r.choice(k + "dofs", {"xyz", "z", "xy"}, "xyz");
    c.clamps.push_back(clamp);
  }
}

std::array<double, 3> triple(TomlReader& r, const std::string& key, std::array<double, 3> fallback) {
  const auto v = r.reals(key, Range{}, std::vector<double>(fallback.begin(), fallback.end()));
  if (v.size() != 3) r.fail(key, "expected [x, y, z]");
  return {v[0], v[1], v[2]};
}

void read_truth(TomlReader& r, Case& c) {
  c.has_truth = r.has("truth.parity") || r.has("truth.max_degree") || r.has("truth.sigma11") || r.has("truth.sigma22") || r.has("truth.table");
  c.truth_amplitude = r.real("truth.amplitude", Range::closed(-100, 100), 1.0);
  if (!c.has_truth) return;
  c.truth_parity = r.choice("truth.parity", {"even", "odd", "all"}, c.parity);
  c.truth_max_degree = static_cast<int>(r.integer("truth.max_degree", c.truth_parity == "odd" ? 3 : 2, 20));
  if (r.has("truth.table")) {
    c.truth_table = relative_to(r.origin(), r.text("truth.table"));
    if (r.has("truth.sigma11") || r.has("truth.sigma22")) r.fail("truth.table", "give either a table or sigma11/sigma22 coefficients, not both");
    return;
  }
  read_coefficients(r, "truth", c.truth_parity, c.truth_max_degree, c.truth_sigma11, c.truth_sigma22);
}

void read_closed_loop(TomlReader& r, Case& c) {
  c.sensor_offset = triple(r, "sensor.offset", c.sensor_offset);
  c.sensor_angle = r.real("sensor.angle", Range::closed(-180, 180), c.sensor_angle);
  c.sensor_length = r.real("sensor.length", Range::positive(), c.sensor_length);
  c.sensor_points = static_cast<int>(r.integer("sensor.points", 2, 100000, c.sensor_points));
  c.sensor_range = r.real("sensor.range", Range::positive(), c.sensor_range);
  c.sensor_period = r.real("sensor.period", Range::closed(1e-4, 10), c.sensor_period);
  c.sensor_noise = r.real("sensor.noise", Range::closed(0, 10), c.sensor_noise);
  c.sensor_offset_error = triple(r, "sensor.offset_error", c.sensor_offset_error);
  c.sensor_angle_error = r.real("sensor.angle_error", Range::closed(-90, 90), c.sensor_angle_error);
  c.sensor_seed = static_cast<std::uint32_t>(r.integer("sensor.seed", 0, 4294967295LL, c.sensor_seed));
  c.desync = r.real("sync.desync", Range::closed(0, 60), c.desync);
  c.feed_override = r.real("sync.feed_override", Range::open(0, 10), c.feed_override);
  c.sync_machine = r.text("sync.machine", c.sync_machine);
  if (c.sync_machine.size() > 5 && c.sync_machine.ends_with(".toml")) c.sync_machine = relative_to(r.origin(), c.sync_machine).string();
  c.sync_reckoning = r.choice("sync.reckoning", {"machine", "programmed"}, c.sync_reckoning);
  c.correct = r.boolean("control.correct", c.correct);
  c.refresh_rate = r.real("control.refresh_rate", Range::closed(0.01, 10000), c.refresh_rate);
  c.max_offset_rate = r.real("control.max_offset_rate", Range::positive(), c.max_offset_rate);
  c.max_offset = r.real("control.max_offset", Range::non_negative(), c.max_offset);
  c.learning_tolerance = r.real("control.learning_tolerance", Range::positive(), c.learning_tolerance);
  c.learning_window = static_cast<int>(r.integer("control.learning_window", 1, 10000, c.learning_window));
  c.reading_range = r.real("control.reading_range", Range::positive(), c.reading_range);
  c.prior_scale = r.real("control.prior_scale", Range::positive(), c.prior_scale);
  c.use_stock_top = r.boolean("control.use_stock_top", c.use_stock_top);
  c.model_tolerance = r.real("control.model_tolerance", Range::positive(), c.model_tolerance);
  c.replan_tool_diameter = r.real("replan.tool_diameter", Range::closed(0.1, 100), c.replan_tool_diameter);
  c.replan_scallop = r.real("replan.scallop", Range::closed(1e-4, 1), c.replan_scallop);
  c.replan_tolerance = r.real("replan.tolerance", Range::closed(1e-4, 1), c.replan_tolerance);
  c.replan_step = r.real("replan.step", Range::closed(0.01, 100), c.replan_step);
  c.replan_sample_spacing = r.real("replan.sample_spacing", Range::closed(0, 100), c.replan_sample_spacing);
  c.replan_scan_step = r.real("replan.scan_step", Range::closed(0.01, 100), c.replan_scan_step);
  // The same keys and ranges as machine/program_keys.cpp (the case holds plain values: case_file/ reads no machine).
  c.program_tool_number = static_cast<int>(r.integer("program.tool_number", 1, 999, c.program_tool_number));
  c.program_spindle_speed = r.real("program.spindle_speed", Range::closed(0, 200000), c.program_spindle_speed);
  c.program_spindle = r.choice("program.spindle", {"cw", "ccw"}, c.program_spindle);
  c.program_coolant = r.choice("program.coolant", {"off", "flood", "mist"}, c.program_coolant);
  c.program_clearance = r.real("program.clearance", Range::positive(), c.program_clearance);
  c.run_scale = r.choice("run.scale", {"quick", "seed"}, "quick");
  if (r.has("run.quick")) c.run_quick = r.strings("run.quick");
  for (const auto& o : c.run_quick)
    if (o.find('=') == std::string::npos) r.fail("run.quick", "expected \"key=value\" overrides, got '" + o + "'");
  c.path_tolerance = r.real("run.path_tolerance", Range::positive(), c.path_tolerance);
  c.shape_tolerance = r.real("run.shape_tolerance", Range::positive(), c.shape_tolerance);
  c.shape_pass = static_cast<int>(r.integer("run.shape_pass", 1, 100000, c.shape_pass));
  if (r.has("run.shape_vtk_passes"))
    for (double v : r.reals("run.shape_vtk_passes", Range::closed(1, 100000))) {
      if (v != std::floor(v)) r.fail("run.shape_vtk_passes", "expected pass numbers (whole numbers from 1)");
      c.shape_vtk_passes.push_back(static_cast<int>(v));
    }
}

}  // namespace

Case load_case(const std::optional<std::filesystem::path>& path, const std::vector<std::string>& overrides) {
  if (!path) return case_from_text(kDefaultCaseToml, "<embedded default case>", overrides);
  return case_from_text(read_input_file(*path, "case file"), path->string(), overrides);
}

Case case_from_text(const std::string& text, const std::string& origin, const std::vector<std::string>& overrides) {
  TomlReader r(text, origin, overrides);

  Case c;
  c.origin = origin;
  c.name = r.text("name");
  c.description = r.text("description", "");
  read_part(r, c);
  c.young_modulus = r.real("material.young_modulus", Range::positive());
  c.poisson_ratio = r.real("material.poisson_ratio", Range{-1, 0.5, true, true});
  read_solver(r, c);
  read_mesh(r, c);
  read_stress(r, c);
  read_pocket(r, c);
  read_tool(r, c);
  read_path(r, c);
  c.removal_criterion = r.choice("removal.criterion", {"centroid", "volume_fraction"}, "volume_fraction");
  c.voxel_size = r.real("removal.voxel_size", Range::positive(), 0.0);
  c.frames = static_cast<int>(r.integer("removal.frames", 0, 10000, 20));
  read_clamps(r, c);
  read_truth(r, c);
  read_closed_loop(r, c);
  r.finish();
  c.resolved_toml = r.resolved_text();
  return c;
}

}  // namespace drom::case_file
