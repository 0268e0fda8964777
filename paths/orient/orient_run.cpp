#include "paths/orient/orient_run.hpp"

#include "geometry/surface_grid.hpp"
#include "geometry/surface_input.hpp"
#include "machine/cl_data.hpp"
#include "machine/feed_prediction.hpp"
#include "machine/post_processor.hpp"
#include "machine/program_verdict.hpp"
#include "support/atomic_file.hpp"
#include "support/run_folder.hpp"
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
#include <cstdio>
#include <cmath>
#include <functional>
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
using Say = std::function<void(const std::string&)>;
double seconds_since(Clock::time_point t) { return std::chrono::duration<double>(Clock::now() - t).count(); }
}  // namespace

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

// Stage 1: the machine, with the tool's length and the part's origin; a tool longer than the Z stroke
// cannot be mounted.
machine::Machine mount_on_machine(const OrientCase& c, const OrientScene& scene, Eigen::Vector3d& origin) {
  const ToolAssembly& tool = scene.tool;
  origin = c.part_origin.value_or(scene.part_origin);
  std::ostringstream setup_origin;
  setup_origin << std::fixed;
  setup_origin.precision(9);
  setup_origin << "setup.part_origin=[" << origin.x() << ", " << origin.y() << ", " << origin.z() << "]";
  machine::Machine m = machine::load_machine(c.machine, {"setup.tool_length=" + std::to_string(tool.length()), setup_origin.str()});
  const int z = m.joint_of('Z');
  if (z >= 0 && tool.length() >= m.axes[z].max - m.axes[z].min)
    throw InputError(c.origin.string() + ": tool: " + std::to_string(tool.length()) + " mm from tip to holder top is longer than the Z stroke of " + m.name + " (" +
                     std::to_string(m.axes[z].max - m.axes[z].min) + " mm)");
  return m;
}

// A check surface crossing the CL path: the cutter itself would cut it.
void refuse_check_surfaces_on_the_path(const OrientCase& c, const OrientScene& scene, const ClearanceChecker& checker) {
  const ToolAssembly& tool = scene.tool;
  for (std::size_t p = 0; p < scene.passes.size(); ++p) {
    const FramedPath& path = scene.passes[p];
    for (std::size_t i = 0; i < path.cl.size(); ++i) {
      const double d = checker.distance().distance(path.cl[i]);
      if (d < tool.cutter.corner_radius - 1e-3)
        throw InputError(c.origin.string() + ": a check surface crosses the CL path: pass " + std::to_string(p) + " (" + scene.pass_names[p] + ") at s = " +
                         std::to_string(path.s[i]) + " mm is " + std::to_string(d) + " mm from it, inside the cutter (radius " + std::to_string(tool.cutter.corner_radius) + " mm)");
    }
  }
}

// Stage 2's result: what every pass's integration and every pose's check read.
struct Precomputed {
  ObstacleCloud obstacles;
  std::vector<Eigen::Vector3d> nodes;
  std::unique_ptr<ClearanceChecker> checker;
  std::unique_ptr<ForceField> field;
  std::unique_ptr<VoxelField> voxels;
  double distance_seconds = 0, voxel_seconds = 0;
  const ForceField& force() const { return voxels ? static_cast<const ForceField&>(*voxels) : *field; }
};

// Stage 2: obstacles, tool nodes, the distance field (and the path checked against it), the force field.
Precomputed precompute(const OrientCase& c, const OrientScene& scene) {
  Precomputed pre;
  const auto t_pre = Clock::now();
  pre.obstacles = scene_obstacles(scene, c.obstacle_spacing, c.khatib.influence_radius);
  pre.nodes = tool_skin_nodes(scene.tool, c.tool_nodes, c.skin_spacing);
  pre.checker = std::make_unique<ClearanceChecker>(scene, c.clearance);
  refuse_check_surfaces_on_the_path(c, scene, *pre.checker);
  pre.distance_seconds = seconds_since(t_pre);
  const auto t_field = Clock::now();
  if (c.voxel) pre.voxels = std::make_unique<VoxelField>(pre.obstacles, c.khatib, c.voxel_settings);
  else pre.field = std::make_unique<DirectField>(pre.obstacles, c.khatib, c.aggregation);
  pre.voxel_seconds = seconds_since(t_field);
  return pre;
}

// The programmed axis sampled like the integrated one (the model off).
AxisHistory programmed_axis(const OrientCase& c, const FramedPath& path) {
  AxisHistory h;
  const int n = std::max(2, static_cast<int>(std::ceil(path.length() / c.dynamics.output_step)) + 1);
  for (int i = 0; i < n; ++i) {
    AxisSample a;
    a.s = path.length() * i / (n - 1);
    const FramedPath::Frame fr = path.at(a.s);
    a.roll = fr.roll_prog;
    a.pitch = fr.pitch_prog;
    a.axis = a.programmed_axis = tool_rotation(fr, a.roll, a.pitch).col(2);
    a.cl = a.programmed_cl = reference_point(fr, a.axis, c.dynamics.contact_offset);
    h.samples.push_back(a);
  }
  return h;
}

// Stage 3's result.
struct Integration {
  int moved_starts = 0;
  long evaluations = 0, steps = 0;
  double seconds = 0;
};

// Stage 3: every pass integrated (the seed's model), or the programmed axis alone. Passes are
// independent (each starts from its own settled start): integrated in parallel.
Integration integrate_passes(const OrientCase& c, const OrientScene& scene, const Precomputed& pre, const DynamicsSettings& dynamics, tbb::task_arena& arena,
                             const Say& say, bool quiet, std::vector<AxisHistory>& passes) {
  const auto t_poses = Clock::now();
  passes.resize(scene.passes.size());
  std::atomic<std::size_t> finished{0};
  std::atomic<int> moved_starts{0};
  std::mutex progress;
  const std::size_t tenth = std::max<std::size_t>(1, scene.passes.size() / 10);
  const auto one_pass = [&](std::size_t p) {
    if (c.model_on) {
      const std::optional<Eigen::Vector2d> start =
          dynamics.settle_start ? free_start(*pre.checker, scene.passes[p], c.dynamics.contact_offset, std::max(c.clearance.required, 0.0) + kFreeStartMargin)
                                : std::nullopt;
      if (start) ++moved_starts;
      passes[p] = integrate_axis(scene.passes[p], pre.nodes, pre.force(), dynamics, start);
      if (c.smoothing > 0) smooth_axis(passes[p], scene.passes[p], c.smoothing, dynamics);
    } else {
      passes[p] = programmed_axis(c, scene.passes[p]);
    }
    const std::size_t done = ++finished;
    if (!quiet && done % tenth == 0) {
      const std::lock_guard lock(progress);
      say("  " + std::to_string(done) + "/" + std::to_string(scene.passes.size()) + " passes");
    }
  };
  arena.execute([&] { tbb::parallel_for(std::size_t(0), scene.passes.size(), one_pass); });
  Integration r;
  r.moved_starts = moved_starts.load();
  for (const auto& h : passes) {
    r.evaluations += h.rhs_evaluations;
    r.steps += h.steps;
  }
  r.seconds = seconds_since(t_poses);
  return r;
}

// The result's CL points, axes and arc lengths, pass by pass, after the model and as programmed.
struct PassPoses {
  std::vector<std::vector<Eigen::Vector3d>> cl, cl_before, after, before;
  std::vector<std::vector<double>> s;
};

PassPoses pass_poses(const std::vector<AxisHistory>& passes) {
  PassPoses q;
  for (auto* v : {&q.cl, &q.cl_before, &q.after, &q.before}) v->resize(passes.size());
  q.s.resize(passes.size());
  for (std::size_t p = 0; p < passes.size(); ++p)
    for (const auto& a : passes[p].samples) {
      q.cl[p].push_back(a.cl);
      q.cl_before[p].push_back(a.programmed_cl);
      q.after[p].push_back(a.axis);
      q.before[p].push_back(a.programmed_axis);
      q.s[p].push_back(a.s);
    }
  return q;
}

// Stage 4, the proof: clearance and gouging of the corrected and of the programmed axes.
struct ProofTimes {
  double after = 0, before = 0;
};

ProofTimes prove_clearance(const ClearanceChecker& checker, const PassPoses& q, tbb::task_arena& arena, OrientResult& result) {
  ProofTimes t;
  const auto t_check = Clock::now();
  arena.execute([&] { result.after = checker.check_all(q.cl, q.after, q.s); });
  t.after = seconds_since(t_check);
  const auto t_check_before = Clock::now();
  arena.execute([&] { result.before = checker.check_all(q.cl_before, q.before, q.s); });
  t.before = seconds_since(t_check_before);
  return t;
}

// Stage 5's result: the machine's view of the result and of the programmed axes.
struct OnMachine {
  std::vector<AxisKinematics> axes_after;
  double ratio_after[3] = {0, 0, 0}, ratio_before[3] = {0, 0, 0};
  machine::ClProgram program_after;
  std::vector<std::string> unreachable_before;
  double cycle_after = 0, cycle_before = 0;
};

// Stage 5: the rotary axes along the result, before and after, their reach and the cycle times. A pose
// out of the machine's reach is reported with the rest, not thrown: the computation behind it (a
// quarter of an hour on the full impeller) is the programmer's to look at.
OnMachine put_on_machine(const OrientCase& c, const ToolAssembly& tool, const machine::Kinematics& kin, const PassPoses& q, OrientResult& result) {
  const machine::Machine& m = kin.machine();
  std::vector<std::vector<machine::ClPose>> poses_after(q.cl.size()), poses_before(q.cl.size());
  for (std::size_t p = 0; p < q.cl.size(); ++p)
    for (std::size_t i = 0; i < q.cl[p].size(); ++i) {
      poses_after[p].push_back({q.cl[p][i] - tool.cutter.pivot_height() * q.after[p][i], q.after[p][i]});
      poses_before[p].push_back({q.cl_before[p][i] - tool.cutter.pivot_height() * q.before[p][i], q.before[p][i]});
    }
  const double feed = c.dynamics.recall.feed;
  OnMachine on;
  for (std::size_t p = 0; p < q.cl.size(); ++p) {
    on.axes_after.push_back(rotary_kinematics(kin, poses_after[p], q.s[p], feed));
    const AxisKinematics b = rotary_kinematics(kin, poses_before[p], q.s[p], feed);
    for (int d = 0; d < 3; ++d) {
      on.ratio_after[d] = std::max(on.ratio_after[d], on.axes_after.back().worst_ratio[d]);
      on.ratio_before[d] = std::max(on.ratio_before[d], b.worst_ratio[d]);
    }
  }
  on.program_after = cl_program(poses_after, feed);
  const machine::ClProgram program_before = cl_program(poses_before, feed);
  const machine::ClOnMachine on_after = machine::cl_to_machine_program(on.program_after, kin), on_before = machine::cl_to_machine_program(program_before, kin);
  const auto reach = [&](const machine::ClOnMachine& placed) {
    std::vector<std::string> list;
    for (const auto& v : placed.joints.violations) list.push_back("CL point " + std::to_string(v.pose) + " on " + m.name + ": " + v.what);
    return list;
  };
  result.unreachable = reach(on_after);
  on.unreachable_before = reach(on_before);
  on.cycle_after = machine::predict_feed(on_after.program, kin).cycle_time;
  on.cycle_before = machine::predict_feed(on_before.program, kin).cycle_time;
  return on;
}

// The result's extremes: the axis's deviation from the programmed one and its rate, acceleration and
// jerk, and the path's length.
struct OrientationExtremes {
  double deviation = 0, rate = 0, acceleration = 0, jerk = 0, path_length = 0;
};

OrientationExtremes orientation_extremes(const std::vector<AxisHistory>& passes) {
  OrientationExtremes e;
  for (const auto& h : passes) {
    if (!h.samples.empty()) e.path_length += h.samples.back().s;
    for (const auto& a : h.samples) {
      e.deviation = std::max(e.deviation, std::acos(std::clamp(a.axis.dot(a.programmed_axis), -1.0, 1.0)));
      e.rate = std::max(e.rate, std::hypot(a.roll_rate, a.pitch_rate));
      e.acceleration = std::max(e.acceleration, std::hypot(a.roll_acc, a.pitch_acc));
      e.jerk = std::max(e.jerk, std::hypot(a.roll_jerk, a.pitch_jerk));
    }
  }
  return e;
}

json clearance_report_json(const ClearanceReport& r) {
  json v = json::array();
  for (std::size_t k = 0; k < std::min<std::size_t>(r.collisions.size(), 200); ++k)
    v.push_back({{"pass", r.collisions[k].pass}, {"s_mm", r.collisions[k].s}, {"clearance_mm", r.collisions[k].value}});
  json g = json::array();
  for (std::size_t k = 0; k < std::min<std::size_t>(r.gouges.size(), 200); ++k)
    g.push_back({{"pass", r.gouges[k].pass}, {"s_mm", r.gouges[k].s}, {"depth_mm", r.gouges[k].value}});
  return json{{"poses", r.poses}, {"worst_clearance_mm", r.worst_clearance}, {"collisions", r.collisions.size()}, {"worst_gouge_mm", r.worst_gouge},
              {"gouges", r.gouges.size()}, {"collision_list", v}, {"gouge_list", g}};
}

// Stage 5b, with [relax]: the programmed axis relaxed under the machine's limits (thesis 003, eq. 5;
// orientation_under_limits.hpp): the contact kept, the tilt (and yaw) fields the machine runs fastest
// within the bounds, pass by pass; then checked for clearance like the field's result. A different
// answer to the same question (which axis along these passes?), reported beside the field's: the
// relaxation knows the machine and not the obstacles, the field the obstacles and not the machine.
struct Relaxation {
  json summary;
  machine::ClProgram program;
};

Relaxation relax_programmed_axes(const OrientCase& c, const OrientScene& scene, const machine::Kinematics& kin, const ClearanceChecker& checker,
                                 tbb::task_arena& arena, OrientResult& result) {
  const Tool& tool = scene.tool.cutter;
  const double feed = c.dynamics.recall.feed;
  std::vector<PassOrientation> relaxed(scene.passes.size());
  std::vector<std::string> errors(scene.passes.size());
  arena.execute([&] {
    tbb::parallel_for(std::size_t(0), scene.passes.size(), [&](std::size_t p) {
      const FramedPath& path = scene.passes[p];
      SurfacePass pass;
      pass.feed = feed;
      std::vector<Orientation> programmed;
      for (std::size_t i = 0; i < path.cl.size(); ++i) {
        const FramedPath::Frame fr = path.at(path.s[i]);
        // The path's CL is the corner circle's centre over the contact: CC + r n.
        pass.points.push_back({path.cl[i] - tool.corner_radius * fr.n, fr.n, fr.f, 0.0});
        const Eigen::Vector3d u = tool_rotation(fr, path.roll_prog[i], path.pitch_prog[i]).col(2);
        programmed.push_back({std::acos(std::clamp(u.dot(fr.n), -1.0, 1.0)), std::atan2(u.dot(fr.n.cross(fr.f)), u.dot(fr.f))});
      }
      try {
        relaxed[p] = relax_orientation(pass, tool, programmed, kin, *c.relax);
      } catch (const InputError& e) {
        errors[p] = e.what();
      }
    });
  });
  PassPoses q;
  for (auto* v : {&q.cl, &q.after}) v->resize(scene.passes.size());
  q.s.resize(scene.passes.size());
  result.relaxed.resize(scene.passes.size());
  double time_before = 0, time_after = 0;
  int evaluations = 0;
  json failed = json::array();
  for (std::size_t p = 0; p < scene.passes.size(); ++p) {
    if (!errors[p].empty()) {
      failed.push_back({{"pass", p}, {"error", errors[p]}});
      continue;
    }
    result.relaxed[p] = relaxed[p].poses;
    time_before += relaxed[p].time_before, time_after += relaxed[p].time_after, evaluations += relaxed[p].evaluations;
    for (std::size_t i = 0; i < relaxed[p].poses.size(); ++i) {
      const machine::ClPose& pose = relaxed[p].poses[i];
      q.cl[p].push_back(pose.tip + tool.pivot_height() * pose.axis);
      q.after[p].push_back(pose.axis);
      q.s[p].push_back(scene.passes[p].s[i]);
    }
  }
  arena.execute([&] { result.relaxed_check = checker.check_all(q.cl, q.after, q.s); });
  Relaxation r;
  r.program = cl_program(result.relaxed, feed);
  const machine::ClOnMachine on = machine::cl_to_machine_program(r.program, kin);
  const RelaxationSettings& rs = *c.relax;
  const double deg = kDeg;
  r.summary = {{"model", "thesis 003 eq. 5: the programmed axis's tilt (and yaw) relaxed under the machine's limits, the contact kept"},
               {"tilt_deg", {rs.tilt_min * deg, rs.tilt_max * deg}},
               {"free_yaw", rs.free_yaw},
               {"passes_relaxed", scene.passes.size() - failed.size()},
               {"passes_failed", failed},
               {"time_programmed_s", time_before},
               {"time_relaxed_s", time_after},
               {"evaluations", evaluations},
               {"cycle_time_relaxed_s", on.joints.violations.empty() ? machine::predict_feed(on.program, kin).cycle_time : -1.0},
               {"unreachable_poses", on.joints.violations.size()},
               {"clearance", clearance_report_json(result.relaxed_check)},
               {"verdict", !failed.empty() || !on.joints.violations.empty() ? "OUT OF THE MACHINE'S REACH"
                           : !result.relaxed_check.collisions.empty()        ? "COLLISIONS"
                                                                             : "collision-free"}};
  return r;
}

json machine_json(const machine::Machine& m, const Eigen::Vector3d& origin, const OnMachine& on, const OrientResult& result) {
  json j;
  const char* names[3] = {"velocity", "acceleration", "jerk"};
  for (int d = 0; d < 3; ++d) {
    j["max_ratio_to_limit_after"][names[d]] = on.ratio_after[d];
    j["max_ratio_to_limit_programmed"][names[d]] = on.ratio_before[d];
  }
  j["name"] = m.name;
  j["part_origin_mm"] = {origin.x(), origin.y(), origin.z()};
  j["cycle_time_programmed_s"] = on.cycle_before;
  j["cycle_time_after_s"] = on.cycle_after;
  const auto first_of = [](const std::vector<std::string>& list) {
    return std::vector<std::string>(list.begin(), list.begin() + static_cast<std::ptrdiff_t>(std::min<std::size_t>(list.size(), 20)));
  };
  j["unreachable_poses_after"] = result.unreachable.size();
  j["unreachable_list_after"] = first_of(result.unreachable);
  j["unreachable_poses_programmed"] = on.unreachable_before.size();
  j["unreachable_list_programmed"] = first_of(on.unreachable_before);
  return j;
}

// Everything the summary reports, by name.
struct OrientFigures {
  const OrientScene& scene;
  const Precomputed& pre;
  const Integration& integration;
  const ProofTimes& proof;
  const OnMachine& on;
  const machine::Machine& machine;
  const Eigen::Vector3d& origin;
  int threads = 0;
};

json orient_summary(const OrientCase& c, const OrientFigures& f, const OrientationExtremes& e, const OrientResult& result) {
  const OrientScene& scene = f.scene;
  json j;
  j["command"] = "orient";
  j["case"] = c.origin.string();
  j["scene"] = {{"name", scene.name}, {"description", scene.description}, {"passes", scene.passes.size()}, {"path_length_mm", e.path_length},
                {"check_patches", scene.check_patches.size()}, {"check_triangles", scene.check_mesh.triangles.size()}};
  j["model"] = {{"enabled", c.model_on}, {"k_N_mm_per_rad", c.dynamics.recall.stiffness}, {"omega0_rad_s", c.dynamics.recall.omega0()},
                {"J_N_mm_s2", c.dynamics.recall.inertia()}, {"c_N_mm_s", c.dynamics.recall.damping()}, {"eta_N_mm3", c.khatib.eta},
                {"r0_mm", c.khatib.influence_radius}, {"aggregation", aggregation_name(c.aggregation)}, {"moment", moment_model_name(c.dynamics.moment)},
                {"jerk_lag_s", c.dynamics.jerk_lag}, {"obstacle_nodes", f.pre.obstacles.size()}, {"tool_nodes", f.pre.nodes.size()},
                {"integrator", c.dynamics.adaptive ? "ARKODE Dormand-Prince 4(5)" : "RK4"}, {"rhs_evaluations", f.integration.evaluations},
                {"steps", f.integration.steps}, {"starts_moved_clear", f.integration.moved_starts}, {"singular_cone_rad", c.dynamics.singular_cone},
                {"smoothing_mm", c.smoothing}};
  if (c.voxel)
    j["field"] = {{"kind", "voxel"}, {"voxel_mm", c.voxel_settings.voxel}, {"interpolation", interpolation_name(c.voxel_settings.interpolation)},
                  {"near_field_voxels", c.voxel_settings.near_field}, {"stored_corners", f.pre.voxels->stored_corners()},
                  {"pruned_material_corners", f.pre.voxels->pruned_material_corners()}, {"memory_bytes", f.pre.voxels->memory_bytes()}};
  else
    j["field"] = {{"kind", "direct"}};
  j["orientation"] = {{"max_deviation_deg", e.deviation * kDeg}, {"max_rate_rad_s", e.rate}, {"max_acceleration_rad_s2", e.acceleration}, {"max_jerk_rad_s3", e.jerk}};
  j["clearance"] = {{"required_mm", c.clearance.required}, {"distance_voxel_mm", c.clearance.voxel}, {"after", clearance_report_json(result.after)},
                    {"programmed_axis", clearance_report_json(result.before)}};
  j["machine"] = machine_json(f.machine, f.origin, f.on, result);
  j["timing_s"] = {{"distance_field", f.pre.distance_seconds}, {"voxel_field", f.pre.voxel_seconds}, {"poses", f.integration.seconds}, {"clearance_check", f.proof.after},
                   {"clearance_check_programmed", f.proof.before}, {"threads", f.threads}};
  j["verdict"] = !result.after.collisions.empty() ? "COLLISIONS" : !result.unreachable.empty() ? "OUT OF THE MACHINE'S REACH" : "collision-free";
  return j;
}

std::string result_line(const OrientResult& result, const OrientationExtremes& e, const OnMachine& on) {
  return "  max deviation " + std::to_string(e.deviation * kDeg) + " deg; worst clearance " + std::to_string(result.after.worst_clearance) + " mm (" +
         std::to_string(result.after.collisions.size()) + " violations; programmed axis: " + std::to_string(result.before.worst_clearance) + " mm, " +
         std::to_string(result.before.collisions.size()) + " violations); cycle time " + std::to_string(on.cycle_before) + " -> " + std::to_string(on.cycle_after) + " s";
}

// Stage 6, the tables: the CL path with the angles, clearance and gouge (path.vtp), the tool's axis
// every 5 mm (poses.vtp), the angles and the rotary axes along s (angles.csv, axes.csv).
void write_orient_tables(const std::filesystem::path& out, const OrientScene& scene, const machine::Machine& m, const OrientResult& result,
                         const std::vector<AxisKinematics>& axes_after) {
  const ToolAssembly& tool = scene.tool;
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
}

// Stage 6, the pictures: θ and its derivatives along s for the pass that deviates most.
void write_angle_plots(const std::filesystem::path& out, const OrientScene& scene, const std::vector<AxisHistory>& passes, std::vector<std::string>& files) {
  std::size_t worst = 0;
  double worst_dev = -1;
  for (std::size_t p = 0; p < passes.size(); ++p)
    for (const auto& a : passes[p].samples) {
      const double d = std::acos(std::clamp(a.axis.dot(a.programmed_axis), -1.0, 1.0));
      if (d > worst_dev) {
        worst_dev = d;
        worst = p;
      }
    }
  const auto& h = passes[worst].samples;
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
}

}  // namespace

OrientResult run_orient(const OrientCase& c, const OrientOptions& options) {
  const OrientScene scene = build_orient_scene(c);
  tbb::task_arena arena(options.threads > 0 ? options.threads : tbb::task_arena::automatic);
  const Say say = [&](const std::string& line) {
    if (!options.quiet) std::cout << line << std::endl;
  };
  Eigen::Vector3d origin;
  const machine::Machine m = mount_on_machine(c, scene, origin);
  const machine::Kinematics kin(m);
  DynamicsSettings dynamics = c.dynamics;
  dynamics.singular_direction = kin.singular_direction();
  std::optional<RunFolder> folder;  // taken before the work: an output folder that cannot be written is found now
  if (options.write_files) folder.emplace(options.out, RunFolderOptions{.resume = false, .reused = {}, .inputs = {c.origin}});

  const Precomputed pre = precompute(c, scene);
  say("drom orient: " + scene.description + "; " + std::to_string(pre.obstacles.size()) + " obstacle nodes, " + std::to_string(pre.nodes.size()) + " tool nodes, " +
      std::to_string(scene.passes.size()) + " passes");
  OrientResult result;
  const Integration integration = integrate_passes(c, scene, pre, dynamics, arena, say, options.quiet, result.passes);
  const PassPoses poses = pass_poses(result.passes);
  const ProofTimes proof = prove_clearance(*pre.checker, poses, arena, result);
  const OnMachine on = put_on_machine(c, scene.tool, kin, poses, result);

  const OrientationExtremes extremes = orientation_extremes(result.passes);
  result.summary = orient_summary(c, {scene, pre, integration, proof, on, m, origin, arena.max_concurrency()}, extremes, result);
  say(result_line(result, extremes, on));
  char limits[320];
  std::snprintf(limits, sizeof limits,
                "  rotary axes at the programmed feed, demanded over available: velocity %.3gx, acceleration %.3gx, jerk %.3gx (programmed axis: %.3gx, %.3gx, %.3gx)",
                on.ratio_after[0], on.ratio_after[1], on.ratio_after[2], on.ratio_before[0], on.ratio_before[1], on.ratio_before[2]);
  say(limits);
  std::optional<Relaxation> relaxation;
  if (c.relax) {
    relaxation = relax_programmed_axes(c, scene, kin, *pre.checker, arena, result);
    result.summary["relaxed_programmed_axis"] = relaxation->summary;
    say("  the programmed axis relaxed under the limits: " + relaxation->summary["verdict"].get<std::string>() + ", passes " +
        std::to_string(relaxation->summary["time_programmed_s"].get<double>()) + " -> " + std::to_string(relaxation->summary["time_relaxed_s"].get<double>()) + " s");
  }
  if (!options.write_files) return result;
  const std::filesystem::path& out = folder->staging();
  write_file_atomically(out / "cl.csv", machine::cl_csv(on.program_after));
  std::vector<std::string> files{"cl.csv", "path.vtp", "poses.vtp", "angles.csv", "axes.csv"};
  if (result.unreachable.empty()) {
    // Posted, read back and judged (machine/program_verdict.hpp); written only when it stays within reach.
    machine::PostOptions post = c.program;
    post.title = "drom orient " + scene.name;
    post.tool_diameter = 2 * scene.tool.cutter.radius;
    const std::string text = machine::post_process(on.program_after, kin, post);
    const machine::ProgramVerdict verdict = machine::judge_program(text, "program.ngc", kin);
    result.summary["program_verdict"] = verdict.to_json();
    if (verdict.runnable()) {
      write_file_atomically(out / "program.ngc", text);
      files.insert(files.begin() + 1, "program.ngc");
      say("  program.ngc on " + m.name + ": " + verdict.summary_line());
      if (verdict.slows_down()) say("  warning: at its programmed feed the program asks more than the machine's axes give: the machine slows down (the cycle time above is what it reaches)");
    } else {
      result.unreachable.push_back(verdict.beyond_strokes.front().what);
    }
  }
  if (relaxation) {
    write_file_atomically(out / "relaxed_cl.csv", machine::cl_csv(relaxation->program));
    files.push_back("relaxed_cl.csv");
  }
  write_orient_tables(out, scene, m, result, on.axes_after);
  write_angle_plots(out, scene, result.passes, files);
  result.summary["files"] = files;
  result.summary["resolved_case"] = c.resolved;
  write_summary(out, result.summary);
  folder->commit();
  return result;
}

}  // namespace drom::paths
