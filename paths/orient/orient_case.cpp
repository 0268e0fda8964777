#include "paths/orient/orient_case.hpp"

#include "machine/program_keys.hpp"

#include "geometry/surface_grid.hpp"
#include "geometry/surface_input.hpp"
#include "support/input_error.hpp"
#include "support/toml_reader.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <sstream>
#include <type_traits>

namespace drom::paths {

namespace {

std::string count_text(double n) {
  std::ostringstream out;
  out.precision(3);
  out << n;
  return out.str();
}

// The check surfaces' area (mm²), from above: a patch counts as its longest iso-curves' product.
double check_area(const std::vector<CheckPatch>& patches, const TriangleSoup& mesh) {
  double area = 0;
  for (const auto& p : patches) {
    const auto [lu, lv] = geometry::longest_iso_curves(p.surface);
    area += lu * lv;
  }
  for (const auto& t : mesh.triangles)
    area += 0.5 * (mesh.vertices[t[1]] - mesh.vertices[t[0]]).cross(mesh.vertices[t[2]] - mesh.vertices[t[0]]).norm();
  return area;
}

}  // namespace

OrientCase parse_orient_case(const std::string& text, const std::string& origin, const std::vector<std::string>& overrides) {
  TomlReader r(text, origin, overrides);
  OrientCase c;
  c.origin = origin;
  const std::string kind = r.choice("scene.kind", {"bump", "corner", "impeller", "panel"});
  if (kind == "bump") {
    BumpOptions o;
    o.lateral = r.real("scene.lateral", Range::closed(-1e3, 1e3), o.lateral);
    c.scene = o;
  } else if (kind == "corner") {
    CornerOptions o;
    o.stick_out = r.real("scene.stick_out", Range::open_closed(0, 1e3), o.stick_out);
    o.roll = r.real("scene.roll", Range::closed(-1.2, 1.2), o.roll);
    c.scene = o;
  } else if (kind == "impeller") {
    ImpellerOptions o;
    o.blades = static_cast<int>(r.integer("scene.blades", 2, 40, o.blades));
    o.veins = static_cast<int>(r.integer("scene.veins", -1, 40, o.veins));
    o.v_first = r.real("scene.v_first", Range::closed(0, 1), o.v_first);
    o.v_last = r.real("scene.v_last", Range::closed(0, 1), o.v_last);
    o.v_step = r.real("scene.v_step", Range::positive(), o.v_step);
    o.lean = r.real("scene.lean", Range::closed(-0.8, 0.8), o.lean);
    o.lead = r.real("scene.lead", Range::closed(-1, 1), o.lead);
    o.point_spacing = r.real("scene.point_spacing", Range::positive(), o.point_spacing);
    if (o.v_last < o.v_first) r.fail("scene.v_last", "must not be below scene.v_first");
    const int veins = o.veins < 0 ? o.blades : std::min(o.veins, o.blades);
    // Counted before anything is built: a step of 1e-300 must be an error, not a night of allocation.
    const double passes = (o.v_last - o.v_first) / o.v_step * veins;
    if (!(passes <= OrientLimits::passes))
      r.fail("scene.v_step", "asks for " + count_text(passes) + " passes; at most " + count_text(OrientLimits::passes) + " (a larger scene.v_step, or fewer scene.veins)");
    const double points = impeller_cl_points(o);
    if (!(points <= OrientLimits::cl_points))
      r.fail("scene.point_spacing", "asks for " + count_text(points) + " CL points; at most " + count_text(OrientLimits::cl_points) + " (a larger scene.point_spacing)");
    c.scene = o;
  } else {
    PanelOptions o;
    o.stepover = r.real("scene.stepover", Range::positive(), o.stepover);
    o.lead = r.real("scene.lead", Range::closed(-1, 1), o.lead);
    o.clamp_height = r.real("scene.clamp_height", Range::open_closed(0, 1e3), o.clamp_height);
    const double passes = o.pocket / o.stepover;
    if (!(passes <= OrientLimits::passes))
      r.fail("scene.stepover", "asks for " + count_text(passes) + " passes; at most " + count_text(OrientLimits::passes));
    c.scene = o;
  }
  // Extra check surfaces: patches or STL triangles (fixtures, clamps, a machine part).
  const std::filesystem::path base = std::filesystem::path(origin).parent_path();
  for (std::size_t i = 0, n = r.table_count("check_surfaces"); i < n; ++i) {
    const std::string k = "check_surfaces." + std::to_string(i);
    if (r.has(k + ".stl")) {
      std::filesystem::path stl = r.text(k + ".stl");
      if (stl.is_relative()) stl = base / stl;
      c.extra_mesh.append(read_stl_triangles(stl));
    } else {
      const bool flip = r.boolean(k + ".flip", false);
      const geometry::SurfaceInput s = geometry::read_surface(r, k, base);
      c.extra_patches.push_back({k, s.surface, flip});
    }
  }
  ToolAssembly& t = c.tool;
  t = std::visit([](const auto& o) { return default_tool(o); }, c.scene);
  const std::string cutter = r.choice("tool.kind", {"ball", "torus"}, t.cutter.kind == ToolKind::ball ? "ball" : "torus");
  t.cutter.radius = r.real("tool.radius", Range::open_closed(0, 1e3), t.cutter.radius);
  t.cutter.kind = cutter == "ball" ? ToolKind::ball : ToolKind::torus;
  t.cutter.corner_radius = cutter == "ball" ? t.cutter.radius : r.real("tool.corner_radius", Range::positive(), std::min(t.cutter.corner_radius, t.cutter.radius));
  t.flute_length = r.real("tool.flute_length", Range::open_closed(0, 1e4), t.flute_length);
  t.shank_radius = r.real("tool.shank_radius", Range::open_closed(0, 1e3), t.shank_radius);
  t.gauge_length = r.real("tool.stick_out", Range::open_closed(0, 1e4), t.gauge_length);
  if (r.has("tool.holder_z") || r.has("tool.holder_radius")) {
    t.holder.z = r.reals("tool.holder_z", Range::closed(0, 1e4));
    t.holder.radius = r.reals("tool.holder_radius", Range::open_closed(0, 1e3));
  }
  c.tool_nodes = static_cast<int>(r.integer("tool.nodes", 0, static_cast<long long>(OrientLimits::tool_nodes), c.tool_nodes));
  c.skin_spacing = r.real("tool.skin_spacing", Range::positive(), c.skin_spacing);
  try {
    check_avoidance_tool(t);
  } catch (const InputError& e) {
    r.fail("tool", e.what());
  }
  if (c.tool_nodes == 0) {
    const double nodes = tool_skin_area(t) / (c.skin_spacing * c.skin_spacing);
    if (!(nodes <= OrientLimits::tool_nodes))
      r.fail("tool.skin_spacing", "asks for " + count_text(nodes) + " skin nodes; at most " + count_text(OrientLimits::tool_nodes));
  }
  std::visit([&](auto& o) { o.tool = t; }, c.scene);
  // The model.
  RecallParameters& rp = c.dynamics.recall;
  rp.stiffness = r.real("model.k", Range::positive(), rp.stiffness);
  rp.feed = r.real("model.feed", Range::positive(), rp.feed);
  rp.spacing = r.real("model.d0", Range::positive(), rp.spacing);
  c.obstacle_spacing = r.real("model.obstacle_spacing", Range::positive(), rp.spacing);
  c.khatib.eta = r.real("model.eta", Range::positive(), c.khatib.eta);
  c.khatib.influence_radius = r.real("model.r0", Range::open_closed(0, 1e3), c.khatib.influence_radius);
  const std::string agg = r.choice("model.aggregation", {"F1", "F2", "F3"}, "F1");
  c.aggregation = agg == "F1" ? Aggregation::F1 : agg == "F2" ? Aggregation::F2 : Aggregation::F3;
  const std::string moment = r.choice("model.moment", {"G", "lever", "direction"}, "direction");
  c.dynamics.moment = moment == "G" ? MomentModel::PointG : moment == "lever" ? MomentModel::Lever : MomentModel::Direction;
  c.dynamics.lever_g = r.real("model.lever_g", Range::positive(), t.gauge_length - t.cutter.pivot_height());
  c.dynamics.jerk_lag = r.real("model.jerk_lag", Range::non_negative(), 0);
  c.dynamics.contact_offset = t.cutter.radius - t.cutter.corner_radius;  // 0 for a ball
  c.smoothing = r.real("model.smoothing", Range::closed(0, 100), c.smoothing);
  c.dynamics.singular_cone = r.real("model.singular_cone", Range::closed(0, 0.5), c.dynamics.singular_cone);
  c.dynamics.singular_stiffness = r.real("model.singular_stiffness", Range::positive(), c.dynamics.singular_stiffness);
  c.model_on = r.boolean("model.enabled", true);
  // Integration.
  c.dynamics.adaptive = r.choice("integration.method", {"arkode", "rk4"}, "arkode") == "arkode";
  c.dynamics.rk4_step = r.real("integration.rk4_step", Range::positive(), c.dynamics.rk4_step);
  c.dynamics.relative_tolerance = r.real("integration.rtol", Range::positive(), c.dynamics.relative_tolerance);
  c.dynamics.absolute_tolerance = r.real("integration.atol", Range::positive(), c.dynamics.absolute_tolerance);
  c.dynamics.output_step = r.real("integration.output_step", Range::positive(), c.dynamics.output_step);
  c.dynamics.clearance_fraction = r.real("integration.clearance_fraction", Range::open_closed(0, 1), c.dynamics.clearance_fraction);
  // The field.
  c.voxel = r.choice("field.kind", {"direct", "voxel"}, "direct") == "voxel";
  c.voxel_settings.voxel = r.real("field.voxel", Range::positive(), c.voxel_settings.voxel);
  const std::string interp = r.choice("field.interpolation", {"trilinear", "triquadratic", "tricubic"}, "trilinear");
  c.voxel_settings.interpolation = interp == "trilinear" ? VoxelInterpolation::trilinear
                                   : interp == "triquadratic" ? VoxelInterpolation::triquadratic
                                                              : VoxelInterpolation::tricubic;
  c.voxel_settings.near_field = r.real("field.near_field", Range::non_negative(), c.voxel_settings.near_field);
  if (c.voxel && c.aggregation != Aggregation::F1) r.fail("model.aggregation", "the voxel field stores F1 (the seed's eq. 4.2): use F1 or field.kind = \"direct\"");
  // The check and the machine.
  c.clearance.voxel = r.real("check.voxel", Range::positive(), c.clearance.voxel);
  c.clearance.required = r.real("check.required", Range::closed(-1e3, 1e3), c.clearance.required);
  c.clearance.gouge_spacing = r.real("check.gouge_spacing", Range::positive(), c.clearance.gouge_spacing);
  c.machine = r.text("machine.definition", c.machine);
  c.program = machine::read_program_keys(r, {});
  // The relaxation under the machine's limits: its keys are read (and checked) even when it is off.
  constexpr double kRadian = std::numbers::pi / 180;
  RelaxationSettings relax;
  relax.tilt_min = r.real("relax.tilt_min", Range::closed(0, 85), relax.tilt_min / kRadian) * kRadian;
  relax.tilt_max = r.real("relax.tilt_max", Range::open_closed(0, 85), relax.tilt_max / kRadian) * kRadian;
  if (!(relax.tilt_max > relax.tilt_min)) r.fail("relax.tilt_max", "must exceed relax.tilt_min (degrees from the surface normal)");
  relax.free_yaw = r.boolean("relax.free_yaw", relax.free_yaw);
  relax.yaw_range = r.real("relax.yaw_range", Range::open_closed(0, 180), relax.yaw_range / kRadian) * kRadian;
  relax.control_points = static_cast<int>(r.integer("relax.control_points", 4, 200, relax.control_points));
  relax.max_evaluations = static_cast<int>(r.integer("relax.max_evaluations", 10, 100000, relax.max_evaluations));
  if (r.boolean("relax.enabled", false)) c.relax = relax;
  if (r.has("machine.part_origin")) {
    const auto o = r.reals("machine.part_origin", Range::closed(-1e4, 1e4));
    if (o.size() != 3) r.fail("machine.part_origin", "expected [x, y, z] in mm: where the scene's origin sits in the machine's table frame");
    c.part_origin = Eigen::Vector3d(o[0], o[1], o[2]);
  }
  // The extra check surfaces' meshes, counted now (the scene's own surfaces are checked when built).
  const double extra_area = check_area(c.extra_patches, c.extra_mesh);
  if (!(extra_area / (c.obstacle_spacing * c.obstacle_spacing) <= OrientLimits::obstacle_points))
    r.fail("model.obstacle_spacing", "meshes the check surfaces into " + count_text(extra_area / (c.obstacle_spacing * c.obstacle_spacing)) + " points; at most " +
                                         count_text(OrientLimits::obstacle_points));
  r.finish();
  c.resolved = r.resolved_text();
  return c;
}

OrientCase load_orient_case(const std::filesystem::path& path, const std::vector<std::string>& overrides) {
  return parse_orient_case(read_input_file(path, "case file"), path.string(), overrides);
}

OrientScene build_orient_scene(const OrientCase& c) {
  OrientScene scene = std::visit(
      [](const auto& o) {
        using Options = std::decay_t<decltype(o)>;
        if constexpr (std::is_same_v<Options, BumpOptions>) return bump_scene(o);
        else if constexpr (std::is_same_v<Options, CornerOptions>) return corner_scene(o);
        else if constexpr (std::is_same_v<Options, ImpellerOptions>) return impeller_scene(o);
        else return panel_scene(o);
      },
      c.scene);
  scene.check_patches.insert(scene.check_patches.end(), c.extra_patches.begin(), c.extra_patches.end());
  scene.check_mesh.append(c.extra_mesh);
  // What the meshes and grids of the run would hold (OrientLimits).
  const double area = check_area(scene.check_patches, scene.check_mesh);
  const std::string where = c.origin.string() + ": ";
  const double points = area / (c.obstacle_spacing * c.obstacle_spacing);
  if (!(points <= OrientLimits::obstacle_points))
    throw InputError(where + "model.obstacle_spacing: meshes the check surfaces (" + count_text(area) + " mm²) into " + count_text(points) + " points; at most " +
                     count_text(OrientLimits::obstacle_points));
  if (c.voxel) {
    const double h = c.voxel_settings.voxel, voxels = area * 2 * c.khatib.influence_radius / (h * h * h);
    if (!(voxels <= OrientLimits::voxels))
      throw InputError(where + "field.voxel: the force field around the check surfaces would hold " + count_text(voxels) + " voxels; at most " + count_text(OrientLimits::voxels));
  }
  const double h = c.clearance.voxel, band = body_profile(scene.tool).max_radius() + std::max(c.clearance.required, 0.0) + 10;
  const double band_voxels = area * 2 * (band + 2 * h) / (h * h * h);
  if (!(band_voxels <= OrientLimits::voxels))
    throw InputError(where + "check.voxel: the distance check's band would hold " + count_text(band_voxels) + " voxels; at most " + count_text(OrientLimits::voxels));
  return scene;
}

}  // namespace drom::paths
