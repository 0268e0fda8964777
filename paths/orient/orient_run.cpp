#include "paths/orient/orient_run.hpp"

#include "geometry/surface_grid.hpp"
#include "geometry/surface_input.hpp"
#include "machine/cl_data.hpp"
#include "machine/feed_prediction.hpp"
#include "machine/post_processor.hpp"
#include "support/atomic_file.hpp"
#include "support/input_error.hpp"
#include "support/png_plot.hpp"
#include "support/summary.hpp"
#include "support/toml_reader.hpp"
#include "support/vtk_fields.hpp"

#include <Eigen/Geometry>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <fstream>
#include <iostream>
#include <mutex>
#include <numbers>
#include <sstream>
#include <type_traits>

namespace drom::paths {

namespace {
constexpr double kDeg = 180 / std::numbers::pi;
using nlohmann::json;
using Clock = std::chrono::steady_clock;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
}  // namespace

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
  TomlReader r(text, origin);
  for (const auto& o : overrides) r.apply_override(o);
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
  t.gauge_length = r.real("tool.gauge_length", Range::open_closed(0, 1e4), t.gauge_length);
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
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open the case file");
  std::stringstream text;
  text << in.rdbuf();
  return parse_orient_case(text.str(), path.string(), overrides);
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

namespace {

struct AxisKinematics {
  std::vector<double> s;                       // mm
  std::vector<machine::Joints> q, v, a, j;     // rotary joints and their time derivatives at the feed
  double worst_ratio[3] = {0, 0, 0};           // max |q̇|/V, |q̈|/A, |q⃛|/J over the rotary axes
  int worst_axis[3] = {-1, -1, -1};
};

// Rotary axes along a pass at the programmed feed: q(s) by inverse kinematics, time derivatives by
// central differences (v0 d/ds), compared with the machine's limits.
AxisKinematics rotary_kinematics(const machine::Kinematics& kin, const std::vector<machine::ClPose>& poses, const std::vector<double>& s, double feed) {
  AxisKinematics k;
  const machine::JointPath path = machine::inverse_path(kin, poses);
  const std::size_t n = poses.size();
  k.s = s;
  k.q = path.joints;
  const double v0 = feed / 60;
  auto diff = [&](const std::vector<machine::Joints>& x) {
    std::vector<machine::Joints> d(n, machine::Joints::Zero());
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t lo = i == 0 ? 0 : i - 1, hi = std::min(i + 1, n - 1);
      if (hi > lo) d[i] = (x[hi] - x[lo]) / ((s[hi] - s[lo]) / v0);
    }
    return d;
  };
  k.v = diff(k.q);
  k.a = diff(k.v);
  k.j = diff(k.a);
  const machine::Machine& m = kin.machine();
  for (int axis = 3; axis < m.joint_count(); ++axis)
    for (std::size_t i = 0; i < n; ++i) {
      const double r[3] = {std::abs(k.v[i](axis)) / m.axes[axis].velocity, std::abs(k.a[i](axis)) / m.axes[axis].acceleration,
                           std::abs(k.j[i](axis)) / m.axes[axis].jerk};
      for (int d = 0; d < 3; ++d)
        if (r[d] > k.worst_ratio[d]) {
          k.worst_ratio[d] = r[d];
          k.worst_axis[d] = axis;
        }
    }
  return k;
}

machine::ClProgram cl_program(const std::vector<std::vector<machine::ClPose>>& passes, double feed) {
  machine::ClProgram p;
  p.origin = "drom orient";
  for (const auto& pass : passes) {
    if (pass.empty()) continue;
    machine::ClPoint above;
    above.pose = pass.front();
    above.pose.tip += 20 * pass.front().axis;
    above.rapid = true;
    p.points.push_back(above);
    for (const auto& pose : pass) p.points.push_back({pose, feed, false, 0});
    machine::ClPoint retract;
    retract.pose = pass.back();
    retract.pose.tip += 20 * pass.back().axis;
    retract.feed = feed;
    p.points.push_back(retract);
  }
  return p;
}

// The pendulum cannot recover a start that collides: a node behind a wall's face is pushed deeper by
// the face's obstacles, and the exact field's 1/r³ kick can fling the axis over the wall (the panel's
// first pass, with the holder in a clamp jaw at s = 0, settled 75° over it). So when the programmed
// axis collides at s = 0, or comes within `margin` of it, the pendulum is released from the nearest
// axis clear by `margin` instead: rings of growing tilt about the programmed axis (1° apart, 36
// azimuths), measured by the clearance check (no mesh-node luck); the first ring with a pose clear by
// `margin` gives its clearest pose.
constexpr double kFreeStartMargin = 1.0;  // mm over check.required: a start closer than this is moved, and keeps it

std::optional<Eigen::Vector2d> free_start(const ClearanceChecker& checker, const FramedPath& path, double contact_offset, double margin) {
  const FramedPath::Frame fr = path.at(0);
  const auto clearance = [&](double roll, double pitch) {
    const Eigen::Vector3d axis = tool_rotation(fr, roll, pitch).col(2);
    return checker.check(reference_point(fr, axis, contact_offset), axis).clearance;
  };
  if (clearance(fr.roll_prog, fr.pitch_prog) >= margin) return std::nullopt;
  constexpr double degree = std::numbers::pi / 180;
  for (int ring = 1; ring <= 90; ++ring) {
    double best = -1e300;
    Eigen::Vector2d best_angles = Eigen::Vector2d::Zero();
    for (int k = 0; k < 36; ++k) {
      const double phi = k * 10 * degree;
      const Eigen::Vector2d angles(fr.roll_prog + ring * degree * std::cos(phi), fr.pitch_prog + ring * degree * std::sin(phi));
      const double c = clearance(angles(0), angles(1));
      if (c > best) {
        best = c;
        best_angles = angles;
      }
    }
    if (best >= margin) return best_angles;
  }
  return std::nullopt;  // none within 90°: the programmed start, and the check will report it
}

}  // namespace

OrientResult run_orient(const OrientCase& c, const OrientOptions& options) {
  const OrientScene scene = build_orient_scene(c);
  const ToolAssembly& tool = scene.tool;
  tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
  auto say = [&](const std::string& line) {
    if (!options.quiet) std::cout << line << std::endl;
  };
  // The machine first: a tool longer than the Z stroke cannot be mounted.
  const Eigen::Vector3d origin = c.part_origin.value_or(scene.part_origin);
  std::ostringstream setup_origin;
  setup_origin << std::fixed;
  setup_origin.precision(9);
  setup_origin << "setup.part_origin=[" << origin.x() << ", " << origin.y() << ", " << origin.z() << "]";
  machine::Machine m = machine::load_machine(c.machine, {"setup.tool_length=" + std::to_string(tool.length()), setup_origin.str()});
  {
    const int z = m.joint_of('Z');
    if (z >= 0 && tool.length() >= m.axes[z].max - m.axes[z].min)
      throw InputError(c.origin.string() + ": tool: " + std::to_string(tool.length()) + " mm from tip to holder top is longer than the Z stroke of " + m.name + " (" +
                       std::to_string(m.axes[z].max - m.axes[z].min) + " mm)");
  }
  const machine::Kinematics kin(m);
  DynamicsSettings dynamics = c.dynamics;
  dynamics.singular_direction = kin.singular_direction();

  // Precompute: obstacles, tool nodes, the distance field, the voxel field.
  const auto t_pre = Clock::now();
  const ObstacleCloud obstacles = scene_obstacles(scene, c.obstacle_spacing, c.khatib.influence_radius);
  const std::vector<Eigen::Vector3d> nodes = tool_skin_nodes(tool, c.tool_nodes, c.skin_spacing);
  const ClearanceChecker checker(scene, c.clearance);
  // A check surface crossing the CL path: the cutter itself would cut it.
  for (std::size_t p = 0; p < scene.passes.size(); ++p) {
    const FramedPath& path = scene.passes[p];
    for (std::size_t i = 0; i < path.cl.size(); ++i) {
      const double d = checker.distance().distance(path.cl[i]);
      if (d < tool.cutter.corner_radius - 1e-3)
        throw InputError(c.origin.string() + ": a check surface crosses the CL path: pass " + std::to_string(p) + " (" + scene.pass_names[p] + ") at s = " +
                         std::to_string(path.s[i]) + " mm is " + std::to_string(d) + " mm from it, inside the cutter (radius " + std::to_string(tool.cutter.corner_radius) + " mm)");
    }
  }
  const double t_distance = seconds_since(t_pre);
  const auto t_field = Clock::now();
  std::unique_ptr<ForceField> field;
  std::unique_ptr<VoxelField> voxels;
  if (c.voxel) {
    voxels = std::make_unique<VoxelField>(obstacles, c.khatib, c.voxel_settings);
  } else {
    field = std::make_unique<DirectField>(obstacles, c.khatib, c.aggregation);
  }
  const ForceField& force = c.voxel ? static_cast<const ForceField&>(*voxels) : *field;
  const double t_voxel = seconds_since(t_field);
  say("drom orient: " + scene.description + "; " + std::to_string(obstacles.size()) + " obstacle nodes, " + std::to_string(nodes.size()) + " tool nodes, " +
      std::to_string(scene.passes.size()) + " passes");

  // Poses: every pass integrated (the seed's model), or the programmed axis alone.
  const auto t_poses = Clock::now();
  OrientResult result;
  result.passes.resize(scene.passes.size());
  // Passes are independent (each starts from its own settled start): integrated in parallel.
  std::atomic<std::size_t> finished{0};
  std::atomic<int> moved_starts{0};
  std::mutex progress;
  const std::size_t tenth = std::max<std::size_t>(1, scene.passes.size() / 10);
  const auto one_pass = [&](std::size_t p) {
    if (c.model_on) {
      const std::optional<Eigen::Vector2d> start =
          dynamics.settle_start ? free_start(checker, scene.passes[p], c.dynamics.contact_offset, std::max(c.clearance.required, 0.0) + kFreeStartMargin)
                                : std::nullopt;
      if (start) ++moved_starts;
      result.passes[p] = integrate_axis(scene.passes[p], nodes, force, dynamics, start);
      if (c.smoothing > 0) smooth_axis(result.passes[p], scene.passes[p], c.smoothing, dynamics);
    } else {
      // The programmed axis sampled like the integrated one.
      const FramedPath& path = scene.passes[p];
      const int n = std::max(2, static_cast<int>(std::ceil(path.length() / c.dynamics.output_step)) + 1);
      for (int i = 0; i < n; ++i) {
        AxisSample a;
        a.s = path.length() * i / (n - 1);
        const FramedPath::Frame fr = path.at(a.s);
        a.roll = fr.roll_prog;
        a.pitch = fr.pitch_prog;
        a.axis = a.programmed_axis = tool_rotation(fr, a.roll, a.pitch).col(2);
        a.cl = a.programmed_cl = reference_point(fr, a.axis, c.dynamics.contact_offset);
        result.passes[p].samples.push_back(a);
      }
    }
    const std::size_t done = ++finished;
    if (!options.quiet && done % tenth == 0) {
      const std::lock_guard lock(progress);
      say("  " + std::to_string(done) + "/" + std::to_string(scene.passes.size()) + " passes");
    }
  };
  arena.execute([&] { tbb::parallel_for(std::size_t(0), scene.passes.size(), one_pass); });
  long evaluations = 0, steps = 0;
  for (const auto& h : result.passes) {
    evaluations += h.rhs_evaluations;
    steps += h.steps;
  }
  const double t_pose = seconds_since(t_poses);

  // The proof: clearance and gouging of the corrected and of the programmed axes.
  const auto t_check = Clock::now();
  std::vector<std::vector<Eigen::Vector3d>> cl(result.passes.size()), cl_before(result.passes.size()), after(result.passes.size()), before(result.passes.size());
  std::vector<std::vector<double>> s(result.passes.size());
  for (std::size_t p = 0; p < result.passes.size(); ++p)
    for (const auto& a : result.passes[p].samples) {
      cl[p].push_back(a.cl);
      cl_before[p].push_back(a.programmed_cl);
      after[p].push_back(a.axis);
      before[p].push_back(a.programmed_axis);
      s[p].push_back(a.s);
    }
  arena.execute([&] { result.after = checker.check_all(cl, after, s); });
  const double t_clear = seconds_since(t_check);
  const auto t_check_before = Clock::now();
  arena.execute([&] { result.before = checker.check_all(cl_before, before, s); });
  const double t_clear_before = seconds_since(t_check_before);

  // The machine: axes along the result, before and after, and the cycle times.
  std::vector<std::vector<machine::ClPose>> poses_after(cl.size()), poses_before(cl.size());
  for (std::size_t p = 0; p < cl.size(); ++p)
    for (std::size_t i = 0; i < cl[p].size(); ++i) {
      poses_after[p].push_back({cl[p][i] - tool.cutter.pivot_height() * after[p][i], after[p][i]});
      poses_before[p].push_back({cl_before[p][i] - tool.cutter.pivot_height() * before[p][i], before[p][i]});
    }
  const double feed = c.dynamics.recall.feed;
  json machine_json;
  std::vector<AxisKinematics> axes_after;
  double ratio_after[3] = {0, 0, 0}, ratio_before[3] = {0, 0, 0};
  for (std::size_t p = 0; p < cl.size(); ++p) {
    axes_after.push_back(rotary_kinematics(kin, poses_after[p], s[p], feed));
    const AxisKinematics b = rotary_kinematics(kin, poses_before[p], s[p], feed);
    for (int d = 0; d < 3; ++d) {
      ratio_after[d] = std::max(ratio_after[d], axes_after.back().worst_ratio[d]);
      ratio_before[d] = std::max(ratio_before[d], b.worst_ratio[d]);
    }
  }
  const machine::ClProgram program_after = cl_program(poses_after, feed), program_before = cl_program(poses_before, feed);
  const machine::ClOnMachine on_after = machine::cl_to_machine_program(program_after, kin), on_before = machine::cl_to_machine_program(program_before, kin);
  // A pose out of the machine's reach is reported with the rest, not thrown: the computation behind it
  // (a quarter of an hour on the full impeller) is the programmer's to look at.
  const auto reach = [&](const machine::ClOnMachine& on) {
    std::vector<std::string> list;
    for (const auto& v : on.joints.violations) list.push_back("CL point " + std::to_string(v.pose) + " on " + m.name + ": " + v.what);
    return list;
  };
  result.unreachable = reach(on_after);
  const std::vector<std::string> unreachable_before = reach(on_before);
  const double cycle_after = machine::predict_feed(on_after.program, kin).cycle_time;
  const double cycle_before = machine::predict_feed(on_before.program, kin).cycle_time;

  // Summary.
  double max_dev = 0, max_rate = 0, max_acc = 0, max_jerk = 0, path_length = 0;
  for (const auto& h : result.passes) {
    if (!h.samples.empty()) path_length += h.samples.back().s;
    for (const auto& a : h.samples) {
      max_dev = std::max(max_dev, std::acos(std::clamp(a.axis.dot(a.programmed_axis), -1.0, 1.0)));
      max_rate = std::max(max_rate, std::hypot(a.roll_rate, a.pitch_rate));
      max_acc = std::max(max_acc, std::hypot(a.roll_acc, a.pitch_acc));
      max_jerk = std::max(max_jerk, std::hypot(a.roll_jerk, a.pitch_jerk));
    }
  }
  json j;
  j["command"] = "orient";
  j["case"] = c.origin.string();
  j["scene"] = {{"name", scene.name}, {"description", scene.description}, {"passes", scene.passes.size()}, {"path_length_mm", path_length},
                {"check_patches", scene.check_patches.size()}, {"check_triangles", scene.check_mesh.triangles.size()}};
  j["model"] = {{"enabled", c.model_on}, {"k_N_mm_per_rad", c.dynamics.recall.stiffness}, {"omega0_rad_s", c.dynamics.recall.omega0()},
                {"J_N_mm_s2", c.dynamics.recall.inertia()}, {"c_N_mm_s", c.dynamics.recall.damping()}, {"eta_N_mm3", c.khatib.eta},
                {"r0_mm", c.khatib.influence_radius}, {"aggregation", aggregation_name(c.aggregation)}, {"moment", moment_model_name(c.dynamics.moment)},
                {"jerk_lag_s", c.dynamics.jerk_lag}, {"obstacle_nodes", obstacles.size()}, {"tool_nodes", nodes.size()},
                {"integrator", c.dynamics.adaptive ? "ARKODE Dormand-Prince 4(5)" : "RK4"}, {"rhs_evaluations", evaluations}, {"steps", steps},
                {"starts_moved_clear", moved_starts.load()}, {"singular_cone_rad", c.dynamics.singular_cone}, {"smoothing_mm", c.smoothing}};
  if (c.voxel)
    j["field"] = {{"kind", "voxel"}, {"voxel_mm", c.voxel_settings.voxel}, {"interpolation", interpolation_name(c.voxel_settings.interpolation)},
                  {"near_field_voxels", c.voxel_settings.near_field},
                  {"stored_corners", voxels->stored_corners()}, {"pruned_material_corners", voxels->pruned_material_corners()}, {"memory_bytes", voxels->memory_bytes()}};
  else
    j["field"] = {{"kind", "direct"}};
  j["orientation"] = {{"max_deviation_deg", max_dev * kDeg}, {"max_rate_rad_s", max_rate}, {"max_acceleration_rad_s2", max_acc}, {"max_jerk_rad_s3", max_jerk}};
  auto report_json = [](const ClearanceReport& r) {
    json v = json::array();
    for (std::size_t k = 0; k < std::min<std::size_t>(r.collisions.size(), 200); ++k)
      v.push_back({{"pass", r.collisions[k].pass}, {"s_mm", r.collisions[k].s}, {"clearance_mm", r.collisions[k].value}});
    json g = json::array();
    for (std::size_t k = 0; k < std::min<std::size_t>(r.gouges.size(), 200); ++k)
      g.push_back({{"pass", r.gouges[k].pass}, {"s_mm", r.gouges[k].s}, {"depth_mm", r.gouges[k].value}});
    return json{{"poses", r.poses}, {"worst_clearance_mm", r.worst_clearance}, {"collisions", r.collisions.size()}, {"worst_gouge_mm", r.worst_gouge},
                {"gouges", r.gouges.size()}, {"collision_list", v}, {"gouge_list", g}};
  };
  j["clearance"] = {{"required_mm", c.clearance.required}, {"distance_voxel_mm", c.clearance.voxel}, {"after", report_json(result.after)},
                    {"programmed_axis", report_json(result.before)}};
  const char* names[3] = {"velocity", "acceleration", "jerk"};
  for (int d = 0; d < 3; ++d) {
    machine_json["max_ratio_to_limit_after"][names[d]] = ratio_after[d];
    machine_json["max_ratio_to_limit_programmed"][names[d]] = ratio_before[d];
  }
  machine_json["name"] = m.name;
  machine_json["part_origin_mm"] = {origin.x(), origin.y(), origin.z()};
  machine_json["cycle_time_programmed_s"] = cycle_before;
  machine_json["cycle_time_after_s"] = cycle_after;
  const auto first_of = [](const std::vector<std::string>& list) {
    return std::vector<std::string>(list.begin(), list.begin() + static_cast<std::ptrdiff_t>(std::min<std::size_t>(list.size(), 20)));
  };
  machine_json["unreachable_poses_after"] = result.unreachable.size();
  machine_json["unreachable_list_after"] = first_of(result.unreachable);
  machine_json["unreachable_poses_programmed"] = unreachable_before.size();
  machine_json["unreachable_list_programmed"] = first_of(unreachable_before);
  j["machine"] = machine_json;
  j["timing_s"] = {{"distance_field", t_distance}, {"voxel_field", t_voxel}, {"poses", t_pose}, {"clearance_check", t_clear},
                   {"clearance_check_programmed", t_clear_before}, {"threads", arena.max_concurrency()}};
  j["verdict"] = !result.after.collisions.empty() ? "COLLISIONS" : !result.unreachable.empty() ? "OUT OF THE MACHINE'S REACH" : "collision-free";
  result.summary = j;
  say("  max deviation " + std::to_string(max_dev * kDeg) + " deg; worst clearance " + std::to_string(result.after.worst_clearance) + " mm (" +
      std::to_string(result.after.collisions.size()) + " violations; programmed axis: " + std::to_string(result.before.worst_clearance) + " mm, " +
      std::to_string(result.before.collisions.size()) + " violations); cycle time " + std::to_string(cycle_before) + " -> " + std::to_string(cycle_after) + " s");
  if (!options.write_files) return result;

  // Files.
  const std::filesystem::path& out = options.out;
  std::filesystem::create_directories(out);
  write_file_atomically(out / "cl.csv", machine::cl_csv(program_after));
  if (result.unreachable.empty()) write_file_atomically(out / "program.ngc", machine::post_process(program_after, kin, {"drom orient " + scene.name}));
  std::ostringstream angles, axes;
  angles << "pass,s_mm,theta_f_rad,theta_t_rad,dtheta_f_rad_s,dtheta_t_rad_s,ddtheta_f_rad_s2,ddtheta_t_rad_s2,dddtheta_f_rad_s3,dddtheta_t_rad_s3,deviation_deg,"
            "active_nodes,clearance_mm,gouge_mm\n";
  axes << "pass,s_mm";
  for (int a = 3; a < m.joint_count(); ++a)
    for (const char* q : {"", "_velocity", "_acceleration", "_jerk"}) axes << "," << m.axes[a].name << q;
  axes << "\n";
  Polylines lines;
  std::vector<Eigen::Vector3d> points;
  std::vector<double> theta_f, theta_t, clearance, gouge, deviation;
  Eigen::VectorXd axis_after, axis_before;
  std::vector<Eigen::Vector3d> after_all, before_all;
  Polylines poses;
  std::vector<Eigen::Vector3d> pose_points;
  std::vector<double> pose_clearance;
  for (std::size_t p = 0; p < result.passes.size(); ++p) {
    std::vector<long long> line;
    double next_pose = 0;
    for (std::size_t i = 0; i < result.passes[p].samples.size(); ++i) {
      const AxisSample& a = result.passes[p].samples[i];
      const PoseCheck& pc = result.after.passes[p][i];
      const double dev = std::acos(std::clamp(a.axis.dot(a.programmed_axis), -1.0, 1.0)) * kDeg;
      angles << p << ',' << a.s << ',' << a.roll << ',' << a.pitch << ',' << a.roll_rate << ',' << a.pitch_rate << ',' << a.roll_acc << ',' << a.pitch_acc << ','
             << a.roll_jerk << ',' << a.pitch_jerk << ',' << dev << ',' << a.active_nodes << ',' << pc.clearance << ',' << pc.gouge_depth << '\n';
      const AxisKinematics& k = axes_after[p];
      axes << p << ',' << a.s;
      for (int ax = 3; ax < m.joint_count(); ++ax) axes << ',' << k.q[i](ax) * kDeg << ',' << k.v[i](ax) * kDeg << ',' << k.a[i](ax) * kDeg << ',' << k.j[i](ax) * kDeg;
      axes << '\n';
      line.push_back(static_cast<long long>(points.size()));
      points.push_back(a.cl);
      theta_f.push_back(a.roll);
      theta_t.push_back(a.pitch);
      clearance.push_back(std::min(pc.clearance, 1e3));
      gouge.push_back(pc.gouge_depth);
      deviation.push_back(dev);
      after_all.push_back(a.axis);
      before_all.push_back(a.programmed_axis);
      if (a.s >= next_pose) {
        next_pose += 5;
        const Eigen::Vector3d tip = a.cl - tool.cutter.pivot_height() * a.axis;
        poses.lines.push_back({static_cast<long long>(pose_points.size()), static_cast<long long>(pose_points.size() + 1)});
        pose_points.push_back(tip);
        pose_points.push_back(tip + tool.length() * a.axis);
        pose_clearance.push_back(std::min(pc.clearance, 1e3));
        pose_clearance.push_back(std::min(pc.clearance, 1e3));
      }
    }
    lines.lines.push_back(line);
  }
  auto matrix = [](const std::vector<Eigen::Vector3d>& v) {
    Eigen::Matrix3Xd m3(3, static_cast<Eigen::Index>(v.size()));
    for (std::size_t i = 0; i < v.size(); ++i) m3.col(static_cast<Eigen::Index>(i)) = v[i];
    return m3;
  };
  auto flat = [](const std::vector<Eigen::Vector3d>& v) {
    Eigen::VectorXd x(static_cast<Eigen::Index>(3 * v.size()));
    for (std::size_t i = 0; i < v.size(); ++i) x.segment<3>(static_cast<Eigen::Index>(3 * i)) = v[i];
    return x;
  };
  lines.points = matrix(points);
  lines.fields.point_scalars = {{"theta_f_rad", theta_f}, {"theta_t_rad", theta_t}, {"clearance_mm", clearance}, {"gouge_mm", gouge}, {"deviation_deg", deviation}};
  lines.fields.point_vectors = {{"tool_axis", flat(after_all)}, {"programmed_axis", flat(before_all)}};
  write_polylines_vtp(out / "path.vtp", lines);
  poses.points = matrix(pose_points);
  poses.fields.point_scalars = {{"clearance_mm", pose_clearance}};
  write_polylines_vtp(out / "poses.vtp", poses);
  write_file_atomically(out / "angles.csv", angles.str());
  write_file_atomically(out / "axes.csv", axes.str());
  std::vector<std::string> files{"cl.csv", "path.vtp", "poses.vtp", "angles.csv", "axes.csv"};
  if (result.unreachable.empty()) files.insert(files.begin() + 1, "program.ngc");
  // θ and its derivatives along s for the pass that deviates most.
  std::size_t worst = 0;
  double worst_dev = -1;
  for (std::size_t p = 0; p < result.passes.size(); ++p)
    for (const auto& a : result.passes[p].samples) {
      const double d = std::acos(std::clamp(a.axis.dot(a.programmed_axis), -1.0, 1.0));
      if (d > worst_dev) {
        worst_dev = d;
        worst = p;
      }
    }
  const auto& h = result.passes[worst].samples;
  const char* titles[4] = {"theta (rad)", "theta rate (rad/s)", "theta acceleration (rad/s^2)", "theta jerk (rad/s^3)"};
  const char* stems[4] = {"angles.png", "angle_rates.png", "angle_accelerations.png", "angle_jerks.png"};
  for (int d = 0; d < 4; ++d) {
    PlotSpec plot;
    plot.title = scene.name + ", pass " + scene.pass_names[worst] + ": " + titles[d];
    plot.x_label = "s (mm)";
    plot.y_label = titles[d];
    PlotSeries f{"roll theta_f", {}, {}, "-"}, t{"pitch theta_t", {}, {}, "-"};
    for (const auto& a : h) {
      f.x.push_back(a.s);
      t.x.push_back(a.s);
      const double vf[4] = {a.roll, a.roll_rate, a.roll_acc, a.roll_jerk}, vt[4] = {a.pitch, a.pitch_rate, a.pitch_acc, a.pitch_jerk};
      f.y.push_back(vf[d]);
      t.y.push_back(vt[d]);
    }
    plot.series = {f, t};
    if (write_png_plot(out / stems[d], plot)) files.push_back(stems[d]);
  }
  j["files"] = files;
  j["resolved_case"] = c.resolved;
  result.summary = j;
  write_summary(out, j);
  return result;
}

}  // namespace drom::paths
