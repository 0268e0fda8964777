#include "paths/copy/copy_settings.hpp"

#include "machine/program_keys.hpp"

#include "support/input_error.hpp"
#include "support/toml_reader.hpp"

#include <cstdio>
#include <sstream>

namespace drom::paths {

namespace {

// The seed's improved hip run (Makki 2009, 4-§4) where it gives a value; ours elsewhere (docs/clouds.md).
CopySettings defaults() {
  CopySettings s;
  s.origin = "<defaults>";
  s.normals.diameter = 7;
  s.normals.grid_step = 0.5;
  s.normals.directions = {Eigen::Vector3d::UnitZ(), Eigen::Vector3d::UnitX(), -Eigen::Vector3d::UnitX(), Eigen::Vector3d::UnitY(), -Eigen::Vector3d::UnitY()};
  // Every 10 degrees both ways (the seed's hemisphere grid, 648 directions): the hip's 30 degrees of
  // tilt missed the directions that let three packets do an undercut's work (issue 45: five at 30).
  s.visibility.phi_step = 10, s.visibility.theta_step = 10;
  // The window: up to the seed's 85° from the normal, and from 0: a ball cuts at its tip on level
  // ground in every 3-axis finish a shop runs, and the seed's hollow cone (5° here) would tilt the
  // tool over a part the vertical sees whole (issue 45). The hollow cone stays a setting.
  s.visibility.cone_min = 0, s.visibility.cone_max = 85;
  s.visibility.graze = 0.05;
  s.finishing.tool.cutter = {ToolKind::ball, 3, 3};
  s.finishing.tool.gauge_length = 40, s.finishing.tool.holder = RevolvedProfile::endless_cylinder(26.5);
  s.finishing.longitudinal_step = 0.2;
  s.finishing.chord_tolerance = 0.01;
  s.finishing.scallop = 0.005;
  s.finishing.transverse = TransverseStep::adaptive;
  s.finishing.transverse_step = 0.2;
  s.roughing.tool.cutter = {ToolKind::torus, 5, 0};
  s.roughing.tool.gauge_length = 40, s.roughing.tool.holder = RevolvedProfile::endless_cylinder(26.5);
  return s;
}

std::string tool_text(const Tool& t) {
  char b[64];
  if (t.kind == ToolKind::ball) std::snprintf(b, sizeof b, "ball:%g", 2 * t.radius);
  else if (t.corner_radius == 0) std::snprintf(b, sizeof b, "flat:%g", 2 * t.radius);
  else std::snprintf(b, sizeof b, "torus:%g:%g", 2 * t.radius, t.corner_radius);
  return b;
}

const char* transverse_name(TransverseStep t) { return t == TransverseStep::adaptive ? "adaptive" : t == TransverseStep::seed_45 ? "seed_45" : "fixed"; }

void read_tool(TomlReader& r, const std::string& table, ToolAssembly& tool) {
  const std::string key = table + ".tool";
  try {
    tool.cutter = parse_tool(r.text(key, tool_text(tool.cutter)), "the tool");
  } catch (const InputError& e) {
    r.fail(key, e.what());
  }
  tool.flute_length = r.real(table + ".flute_length", Range::non_negative(), tool.flute_length);
  tool.shank_radius = r.real(table + ".shank_diameter", Range::non_negative(), 2 * tool.shank_radius) / 2;
  tool.gauge_length = r.real(table + ".gauge_length", Range::non_negative(), tool.gauge_length);
  tool.holder = RevolvedProfile::endless_cylinder(r.real(table + ".holder_diameter", Range::non_negative(), 2 * tool.holder_reach()) / 2);
  if (tool.has_holder() && tool.gauge_length <= tool.flutes()) r.fail(table + ".gauge_length", "the holder's face must stand above the flutes (gauge length > flute length)");
}

}  // namespace

std::string default_copy_settings() {
  const CopySettings s = defaults();
  std::ostringstream t;
  const auto& d = s.normals.directions;
  t << "# drom copy: every key and its default (docs/case-files.md, \"drom copy\").\n"
    << "[cloud]\nscale = " << s.scale << "                 # every coordinate multiplied by it (the seed scaled by 7/20 and 1/3)\n"
    << "bad_points = \"drop\"          # NaN/Inf points and far outliers: \"drop\" (counted in summary.json) or \"error\"\n"
    << "rim = \"side\"                # beyond the scan's edge: \"side\" (the part's side, down to the base) or \"open\" (air)\n"
    << "side_depth = 0.0            # mm the side goes below the edge; 0: down to the base's top\n"
    << "completion = true           # creases' lines and points in holes a tool would dip into join the scan\n\n"
    << "[normals]                   # sphere launching (Makki 2009, Algorithm 1)\nsphere_diameter = " << s.normals.diameter << "\ngrid_step = " << s.normals.grid_step
    << "\ndirections = [";
  for (std::size_t i = 0; i < d.size(); ++i) t << (i ? ", " : "") << "[" << d[i].x() << ", " << d[i].y() << ", " << d[i].z() << "]";
  t << "]\nfrom_file = false            # true: the cloud's own normals (PLY nx ny nz, or XYZ columns 4-6) for every point\n\n[visibility]                # directions phi x theta (degrees), tool window [v1, v2]\nphi_step = " << s.visibility.phi_step
    << "\ntheta_step = " << s.visibility.theta_step << "\ncone = [" << s.visibility.cone_min << ", " << s.visibility.cone_max << "]\ngraze = " << s.visibility.graze
    << "                # mm: nearer the tool's body than this is a graze, not a collision\ncheck_travel = true         # the cloud's box within the linear strokes\n\n"
    << "[packets]\ncoverage = " << s.packets.coverage << "\nmax_packets = " << s.packets.max_packets << "\nmin_points = " << s.packets.min_points << "\n\n"
    << "[finishing]\ntool = \"" << tool_text(s.finishing.tool.cutter) << "\"           # ball:D, torus:D:r or flat:D (mm)\nflute_length = 0.0           # 0: 2 R\nshank_diameter = 0.0         # 0: the tool's\n"
    << "gauge_length = " << s.finishing.tool.gauge_length << "          # tip to holder (the seed's L = 40)\nholder_diameter = " << 2 * s.finishing.tool.holder_reach()
    << "\nstep = " << s.finishing.longitudinal_step << "                  # along the passes (mm)\nchord_tolerance = " << s.finishing.chord_tolerance
    << "\nscallop = " << s.finishing.scallop << "\ntransverse = \"" << transverse_name(s.finishing.transverse) << "\"    # adaptive, seed_45 or fixed\ntransverse_step = "
    << s.finishing.transverse_step << "       # fixed only\nsteepest = " << s.finishing.steepest << "              # degrees: steeper contacts do not set the step\nfeed = "
    << s.finishing_feed << "\nclearance = " << s.finishing.clearance << "\n\n"
    << "[roughing]\nenabled = true\ntool = \"" << tool_text(s.roughing.tool.cutter) << "\"\nflute_length = 0.0\nshank_diameter = 0.0\ngauge_length = " << s.roughing.tool.gauge_length
    << "\nholder_diameter = " << 2 * s.roughing.tool.holder_reach() << "\nlongitudinal_step = " << s.roughing.longitudinal_step << "\ntransverse_step = " << s.roughing.transverse_step
    << "\ndepth = " << s.roughing.depth << "\nallowance = " << s.roughing.allowance << "               # mm left for finishing, at least\nvoxel = 0.0                   # 0: min(steps, depth) / 4\nramp_angle = "
    << s.roughing.ramp_angle << "\nfeed = " << s.roughing_feed << "\ntool_number = " << s.roughing_tool_number << "\n\n"
    << "[machine]\nname = \"" << s.machine << "\"      # a cases/machines/ name or a file\nset = []                      # overrides, e.g. [\"axes.A.stroke=[-30, 120]\"]\n\n"
    << "[program]                   # the posted programs (docs/case-files.md, \"[program]\")\ntool_number = " << s.program.tool
    << "              # the finishing tool's T and H (roughing.tool_number: the roughing tool's)\nspindle_speed = 0            # rev/min; 0: 300 m/min on the tool's diameter\n"
    << "spindle = \"cw\"\ncoolant = \"off\"             # off, flood or mist\nclearance = " << s.program.clearance << "               # mm above the highest point: where rapids cross\n\n"
    << "[stock]\nbox = []                      # [x0, x1, y0, y1, z0, z1]; empty: the cloud's box grown by margin\nmargin = " << s.stock_margin
    << "\nbase_is_obstacle = true       # the stock under the cloud stays: never entered\n"
    << "# base_top = 0.0              # z of the base's top (the table the part stands on); unset: the cloud's lowest point\n\n"
    << "# [[fixtures]]                # solids the tool must not enter (part frame)\n# kind = \"box\"                # box = [x0, x1, y0, y1, z0, z1]\n"
    << "# kind = \"cylinder\"           # centre = [x, y, z0], radius, height (along Z)\n";
  return t.str();
}

CopySettings read_copy_settings(const std::string& text, const std::string& origin, const std::vector<std::string>& overrides) {
  CopySettings s = defaults();
  s.origin = text.empty() ? "<defaults>" : origin;
  TomlReader r(text, s.origin, overrides);
  s.scale = r.real("cloud.scale", Range::positive(), s.scale);
  s.bad_points_are_errors = r.choice("cloud.bad_points", {"drop", "error"}, s.bad_points_are_errors ? std::string("error") : std::string("drop")) == "error";
  s.rim_is_side = r.choice("cloud.rim", {"side", "open"}, s.rim_is_side ? std::string("side") : std::string("open")) == "side";
  s.side_depth = r.real("cloud.side_depth", Range::non_negative(), s.side_depth);
  s.completion = r.boolean("cloud.completion", s.completion);

  s.normals.diameter = r.real("normals.sphere_diameter", Range::positive(), s.normals.diameter);
  s.normals.grid_step = r.real("normals.grid_step", Range::positive(), s.normals.grid_step);
  s.normals_from_file = r.boolean("normals.from_file", s.normals_from_file);
  if (r.has("normals.directions")) {
    s.normals.directions.clear();
    for (const auto& row : r.real_rows("normals.directions", 3, Range{})) {
      const Eigen::Vector3d d(row[0], row[1], row[2]);
      if (!(d.norm() > 0)) r.fail("normals.directions", "a launch direction is zero");
      s.normals.directions.push_back(d.normalized());
    }
    if (s.normals.directions.empty()) r.fail("normals.directions", "at least one launch direction");
  }

  s.visibility.phi_step = r.real("visibility.phi_step", Range::open_closed(0, 360), s.visibility.phi_step);
  s.visibility.theta_step = r.real("visibility.theta_step", Range::open_closed(0, 180), s.visibility.theta_step);
  const auto cone = r.reals("visibility.cone", Range::closed(0, 90), std::vector<double>{s.visibility.cone_min, s.visibility.cone_max});
  if (cone.size() != 2 || !(cone[0] < cone[1])) r.fail("visibility.cone", "expected [v1, v2] with 0 <= v1 < v2 <= 90 (degrees)");
  s.visibility.cone_min = cone[0], s.visibility.cone_max = cone[1];
  s.visibility.graze = r.real("visibility.graze", Range::non_negative(), s.visibility.graze);
  s.visibility.check_travel = r.boolean("visibility.check_travel", s.visibility.check_travel);

  s.packets.coverage = r.real("packets.coverage", Range::open_closed(0, 1), s.packets.coverage);
  s.packets.max_packets = static_cast<int>(r.integer("packets.max_packets", 1, 64, s.packets.max_packets));
  s.packets.min_points = static_cast<int>(r.integer("packets.min_points", 1, 1000000000, s.packets.min_points));
  s.packets.cone_middle = 0.5 * (s.visibility.cone_min + s.visibility.cone_max);

  read_tool(r, "finishing", s.finishing.tool);
  s.finishing.longitudinal_step = r.real("finishing.step", Range::positive(), s.finishing.longitudinal_step);
  s.finishing.chord_tolerance = r.real("finishing.chord_tolerance", Range::positive(), s.finishing.chord_tolerance);
  s.finishing.scallop = r.real("finishing.scallop", Range::positive(), s.finishing.scallop);
  if (s.finishing.tool.cutter.kind == ToolKind::ball && s.finishing.scallop >= s.finishing.tool.cutter.radius)
    r.fail("finishing.scallop", "must be smaller than the ball's radius");
  const std::string transverse = r.choice("finishing.transverse", {"adaptive", "seed_45", "fixed"}, std::string(transverse_name(s.finishing.transverse)));
  s.finishing.transverse = transverse == "adaptive" ? TransverseStep::adaptive : transverse == "seed_45" ? TransverseStep::seed_45 : TransverseStep::fixed;
  s.finishing.transverse_step = r.real("finishing.transverse_step", Range::positive(), s.finishing.transverse_step);
  s.finishing.steepest = r.real("finishing.steepest", Range::open_closed(0, 90), s.finishing.steepest);
  s.finishing_feed = r.real("finishing.feed", Range::positive(), s.finishing_feed);
  s.finishing.clearance = r.real("finishing.clearance", Range::positive(), s.finishing.clearance);
  s.visibility.tool = s.finishing.tool;

  s.rough = r.boolean("roughing.enabled", s.rough);
  read_tool(r, "roughing", s.roughing.tool);
  s.roughing.longitudinal_step = r.real("roughing.longitudinal_step", Range::positive(), s.roughing.longitudinal_step);
  s.roughing.transverse_step = r.real("roughing.transverse_step", Range::positive(), s.roughing.transverse_step);
  s.roughing.depth = r.real("roughing.depth", Range::positive(), s.roughing.depth);
  s.roughing.allowance = r.real("roughing.allowance", Range::non_negative(), s.roughing.allowance);
  s.roughing.voxel = r.real("roughing.voxel", Range::non_negative(), s.roughing.voxel);
  s.roughing.ramp_angle = r.real("roughing.ramp_angle", Range::open(0, 90), s.roughing.ramp_angle);
  s.roughing_feed = r.real("roughing.feed", Range::positive(), s.roughing_feed);

  s.machine = r.text("machine.name", s.machine);
  if (r.has("machine.set")) s.machine_overrides = r.strings("machine.set");
  s.program = machine::read_program_keys(r, s.program);
  s.roughing_tool_number = static_cast<int>(r.integer("roughing.tool_number", 1, 999, s.roughing_tool_number));

  if (r.has("stock.box")) {
    const auto box = r.reals("stock.box", Range{});
    if (!box.empty()) {
      if (box.size() != 6 || !(box[0] < box[1] && box[2] < box[3] && box[4] < box[5])) r.fail("stock.box", "expected [x0, x1, y0, y1, z0, z1] with x0 < x1, y0 < y1, z0 < z1");
      s.stock_lo = Eigen::Vector3d(box[0], box[2], box[4]), s.stock_hi = Eigen::Vector3d(box[1], box[3], box[5]);
    }
  }
  s.stock_margin = r.real("stock.margin", Range::non_negative(), s.stock_margin);
  s.stock_base_is_obstacle = r.boolean("stock.base_is_obstacle", s.stock_base_is_obstacle);
  if (r.has("stock.base_top")) s.stock_base_top = r.real("stock.base_top", Range{});

  for (std::size_t k = 0; k < r.table_count("fixtures"); ++k) {
    const std::string t = "fixtures." + std::to_string(k) + ".";
    Obstacle o;
    o.name = "fixture " + std::to_string(k + 1);
    const std::string kind = r.choice(t + "kind", {"box", "cylinder"});
    if (kind == "box") {
      const auto box = r.reals(t + "box", Range{});
      if (box.size() != 6 || !(box[0] < box[1] && box[2] < box[3] && box[4] < box[5])) r.fail(t + "box", "expected [x0, x1, y0, y1, z0, z1] with x0 < x1, y0 < y1, z0 < z1");
      o.lo = Eigen::Vector3d(box[0], box[2], box[4]), o.hi = Eigen::Vector3d(box[1], box[3], box[5]);
    } else {
      o.kind = Obstacle::Kind::cylinder;
      const auto c = r.reals(t + "centre", Range{});
      if (c.size() != 3) r.fail(t + "centre", "expected [x, y, z0] (the base's centre)");
      o.lo = Eigen::Vector3d(c[0], c[1], c[2]);
      o.hi = Eigen::Vector3d(r.real(t + "radius", Range::positive()), 0, c[2] + r.real(t + "height", Range::positive()));
    }
    s.fixtures.push_back(o);
  }
  r.finish();
  return s;
}

}  // namespace drom::paths
