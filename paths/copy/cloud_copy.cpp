#include "paths/copy/cloud_copy.hpp"

#include "geometry/cloud_bins.hpp"
#include "geometry/cloud_cells.hpp"
#include "geometry/cloud_creases.hpp"
#include "geometry/cloud_kdtree.hpp"
#include "geometry/cloud_holes.hpp"
#include "geometry/cloud_noise.hpp"
#include "geometry/cloud_noise_floor.hpp"
#include "geometry/cloud_rim.hpp"
#include "geometry/cloud_voxel_map.hpp"
#include "machine/feed_prediction.hpp"
#include "machine/post_processor.hpp"
#include "paths/copy/finishing_floor.hpp"
#include "paths/copy/pca_normals.hpp"
#include "support/input_error.hpp"
#include "support/resources.hpp"

#include <tbb/parallel_for.h>
#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <numbers>
#include <sstream>
#include <cstdio>

namespace drom::paths {

namespace {

class Stopwatch {
 public:
  explicit Stopwatch(std::vector<StageTime>& times) : times_(times) {}
  void stage(const std::string& name) {
    const double wall = seconds_since(start_), cpu = process_cpu_seconds() - cpu_;
    times_.push_back({name, wall, cpu});
    start_ = std::chrono::steady_clock::now();
    cpu_ = process_cpu_seconds();
  }
  // Adds the time since the last mark to `name` (a stage run in pieces, one per packet).
  void add_to(const std::string& name) {
    const double wall = seconds_since(start_), cpu = process_cpu_seconds() - cpu_;
    auto it = std::find_if(times_.begin(), times_.end(), [&](const StageTime& t) { return t.stage == name; });
    if (it == times_.end()) times_.push_back({name, wall, cpu});
    else it->wall += wall, it->cpu += cpu;
    start_ = std::chrono::steady_clock::now();
    cpu_ = process_cpu_seconds();
  }

 private:
  std::vector<StageTime>& times_;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
  double cpu_ = process_cpu_seconds();
};

// An operation's CL data, G-code and predicted time on the machine; a post-processor's refusal
// (a pose beyond a stroke) is kept as the operation's error.
void make_program(PacketOperation& op, const CloudPath& path, const Eigen::Matrix3d& frame, double feed, const std::string& title, int tool_number,
                  double tool_radius, const CopySettings& s, const machine::Kinematics& kin) {
  op.path = path;
  op.cl = to_cl_program(path, frame, feed, title);
  if (op.cl.points.empty()) return;
  machine::PostOptions post = s.program;
  post.title = title;
  post.tool = tool_number;
  post.tool_diameter = 2 * tool_radius;
  try {
    op.gcode = machine::post_process(op.cl, kin, post);
    op.verdict = machine::judge_program(op.gcode, title, kin);
    op.cycle_time = op.verdict->cycle_time;
    if (!op.verdict->runnable()) {
      op.error = op.verdict->beyond_strokes.front().what;
      op.gcode.clear();
    }
  } catch (const InputError& e) {
    op.gcode.clear();
    op.error = e.what();
  }
}

// A program with a move the whole-tool check found deeper into the scan than the tolerance is not
// posted (issue 45: a number in summary.json was not enough): the rest of the copy is, and the run
// ends with exit 3.
void refuse_if_over(PacketOperation& op, const Eigen::Matrix3d& frame, double tolerance) {
  if (!op.error.empty()) return;
  op.error = refusal(op.check, frame, tolerance);
  if (!op.error.empty()) op.gcode.clear();
}

using Say = std::function<void(const std::string&)>;

// The spacing obstacles and the part's side are sampled at: a ball of corner radius r dips between
// points h apart on a plane by r - sqrt(r^2 - h^2 / 2); h = sqrt(r Tu) keeps that under Tu / 2 (a flat
// end mill's edge is taken as a quarter of its radius round). Never coarser than a third of a radius.
double obstacle_spacing(const CopySettings& s) {
  const Tool& f = s.finishing.tool.cutter;
  const double r = std::max(f.corner_radius, f.radius / 4);
  return std::min({f.radius / 3, s.roughing.tool.cutter.radius / 3, std::sqrt(r * s.finishing.chord_tolerance)});
}

// The widest hole a scan may keep: a ball of corner radius r dips rho^2 / 2r where the nearest points
// stand rho from its lowest point; rho = sqrt(r Tu / 2) keeps that to Tu / 4, the share of Tu the
// chord tests leave to the scan's gaps (cloud_finishing.hpp).
double hole_radius(const CopySettings& s) {
  const Tool& f = s.finishing.tool.cutter;
  return std::sqrt(std::max(f.corner_radius, f.radius / 4) * s.finishing.chord_tolerance / 2);
}

// Stage 0: the scan's rim, and the part's side below it down to the base (geometry/cloud_rim.hpp).
std::vector<Eigen::Vector3d> find_sides(const geometry::PointCloud& cloud, const geometry::ScanSurvey& survey, const CopySettings& s, CopyResult& out, const Say& say) {
  if (!s.rim_is_side) return {};
  out.rim = geometry::find_rim(cloud.points, survey, out.noise, out.obstacle_spacing, s.finishing.chord_tolerance / 2);
  const std::vector<Eigen::Vector3d> sides = geometry::side_points(out.rim, out.base_top, out.obstacle_spacing, s.side_depth);
  out.side_points = sides.size();
  out.side = sides;
  say("rim: " + std::to_string(out.rim.points.size()) + " points on the scan's edge; the part's side below it, down to " +
      (s.side_depth > 0 ? std::to_string(s.side_depth) + " mm under the edge" : std::string("the base")) + ", as " + std::to_string(sides.size()) + " points");
  return sides;
}

// Stage 0b: the scan completed where a tool would otherwise cut below the surface its points
// describe: its sharp creases' lines (geometry/cloud_creases.hpp), points in its holes
// (geometry/cloud_holes.hpp) and, under noise, its fitted surface lifted (geometry/cloud_noise_floor.hpp). They are part of the scan for the tool to rest on (after the scan's own
// points in the collision set), not rows: normals, visibility and packets stay the scan's own.
std::vector<Eigen::Vector3d> complete(const geometry::PointCloud& cloud, const geometry::ScanSurvey& survey, const CopySettings& s, CopyResult& out, const Say& say) {
  if (!s.completion) return {};
  const geometry::Creases creases = geometry::crease_points(cloud.points, survey, out.noise, out.obstacle_spacing);
  const geometry::FilledHoles holes = geometry::fill_holes(cloud.points, survey, out.hole_radius, out.noise);
  const geometry::NoiseFloor floor = geometry::noise_floor(cloud.points, survey, out.noise);
  out.crease_points = creases.points.size(), out.crease_cells = creases.cells, out.hole_points = holes.points.size();
  out.noise_floor_points = floor.points.size(), out.noise_floor_deviations = floor.deviations;
  for (const auto* added : {&creases.points, &holes.points, &floor.points}) out.completion.insert(out.completion.end(), added->begin(), added->end());
  if (!out.completion.empty())
    say("completion: " + std::to_string(out.crease_points) + " points on " + std::to_string(out.crease_cells) + " cells' creases, " + std::to_string(out.hole_points) +
        " in holes wider than " + std::to_string(out.hole_radius).substr(0, 5) + " mm (spacing " + std::to_string(holes.spacing).substr(0, 5) + " mm, 90 % under " +
        std::to_string(holes.spacing_p90).substr(0, 5) + "), " + std::to_string(out.noise_floor_points) + " on the noise's floor");
  return out.completion;
}

// Stage 1: normals, the cloud's own or by sphere launching (and the PCA estimate beside them).
void find_normals(const geometry::PointCloud& cloud, const std::vector<Eigen::Vector3d>& sides, const CopySettings& s, CopyResult& out, const Say& say) {
  if (s.normals_from_file) {
    if (!cloud.has_normals()) throw InputError(cloud.origin + ": normals.from_file is set but the cloud carries no normals (PLY nx, ny, nz or XYZ columns 4-6)");
    out.normals_from_file = true;
    out.row_points = cloud.points;
    out.row_normals = cloud.normals;
    for (std::size_t i = 0; i < cloud.size(); ++i) out.normals.points.push_back(static_cast<int>(i)), out.normals.hits.push_back(0);
    out.normals.normals = cloud.normals;
    return;
  }
  say("normals: spheres of D" + std::to_string(s.normals.diameter) + " launched along " + std::to_string(s.normals.directions.size()) + " directions");
  out.normals = launch_spheres(cloud.points, s.normals, sides);
  if (out.normals.points.empty()) throw InputError(cloud.origin + ": no sphere landed on the cloud: no normal, nothing to machine (check the sphere diameter and grid step)");
  for (std::size_t k = 0; k < out.normals.points.size(); ++k) out.row_points.push_back(cloud.points[static_cast<std::size_t>(out.normals.points[k])]);
  out.row_normals = out.normals.normals;
  std::vector<Eigen::Vector3d> pca = pca_normals(cloud.points, out.normals.points, 16);
  orient_like(cloud.points, out.normals.points, pca, out.normals);
  double sum = 0;
  for (std::size_t k = 0; k < pca.size(); ++k) sum += angle_between(pca[k], out.normals.normals[k]);
  out.pca_disagreement = sum / static_cast<double>(pca.size()) * 180 / std::numbers::pi;
}

// Stage 2: the obstacles (the stock's base under the cloud, which stays, and the fixtures) sampled
// beside the cloud: every point the tool must not enter.
std::vector<Eigen::Vector3d> collision_points(const geometry::PointCloud& cloud, const std::vector<Eigen::Vector3d>& completion, const std::vector<Eigen::Vector3d>& sides,
                                              const CopySettings& s, CopyResult& out) {
  std::vector<Obstacle> obstacles = s.fixtures;
  if (s.stock_base_is_obstacle && out.stock.lo.z() < out.base_top - 1e-9) {
    Obstacle base;
    base.name = "stock base";
    base.lo = out.stock.lo, base.hi = Eigen::Vector3d(out.stock.hi.x(), out.stock.hi.y(), out.base_top);
    obstacles.push_back(base);
  }
  std::vector<Eigen::Vector3d> collision = cloud.points;
  collision.insert(collision.end(), completion.begin(), completion.end());
  collision.insert(collision.end(), sides.begin(), sides.end());
  for (const auto& o : obstacles) {
    const auto surface = obstacle_surface(o, out.obstacle_spacing);
    collision.insert(collision.end(), surface.begin(), surface.end());
  }
  out.obstacle_points = collision.size() - cloud.size() - completion.size() - sides.size();
  return collision;
}

// Per point: whether the cutter touching it along its normal stays out of the obstacles (by the graze).
std::vector<char> cutter_clears_obstacles(std::span<const Eigen::Vector3d> points, std::span<const Eigen::Vector3d> normals, std::span<const Eigen::Vector3d> obstacles,
                                          const Tool& cutter, double graze) {
  std::vector<char> clear(points.size(), 1);
  if (obstacles.empty()) return clear;
  const geometry::CloudKdTree tree(obstacles);
  const double tube = cutter.kind == ToolKind::ball ? cutter.radius : cutter.corner_radius;
  if (!(tube > graze)) return clear;
  tbb::parallel_for(std::size_t(0), points.size(), [&](std::size_t i) {
    std::vector<int> near;
    tree.within(points[i] + tube * normals[i], tube - graze, near);
    clear[i] = near.empty();
  });
  return clear;
}

// Stage 3: which directions the machine reaches see each point with the whole tool. Returns, per
// point, whether its cutter would enter an obstacle (empty when none would).
std::vector<char> compute_visibility(const std::vector<Eigen::Vector3d>& collision, std::span<const Eigen::Vector3d> obstacles, const CopySettings& s, const machine::Kinematics& kin,
                        CopyResult& out, const Say& say) {
  say("visibility: " + std::to_string(out.row_points.size()) + " points x the (" + std::to_string(static_cast<int>(s.visibility.phi_step)) + ", " +
      std::to_string(static_cast<int>(s.visibility.theta_step)) + ") degree grid");
  VisibilitySettings vis = s.visibility;
  vis.tool = s.finishing.tool;
  vis.machine = &kin;
  out.visibility = visibility_matrix(collision, out.row_points, out.row_normals, vis);
  // A point whose cutter, touching it, would enter an obstacle (the stock's base under a rim that
  // stands on it, the part's side, a fixture) is seen from no direction: the drop would lift the tool
  // off it whatever the direction.
  const std::vector<char> clear = cutter_clears_obstacles(out.row_points, out.row_normals, obstacles, s.finishing.tool.cutter, s.visibility.graze);
  std::vector<char> blocked(clear.size(), 0);
  for (std::size_t i = 0; i < clear.size(); ++i) {
    if (clear[i]) continue;
    ++out.blocked_by_obstacles, blocked[i] = 1;
    for (auto& column : out.visibility.columns) column[i >> 6] &= ~(std::uint64_t{1} << (i & 63));
  }
  if (out.blocked_by_obstacles == 0) blocked.clear();
  return blocked;
}

// The packets' settings with what the cycle criterion's floor needs: the finishing's level-ground
// step at its feed, and a pass's turn as a jerk-limited stop and start on the slowest linear axis.
PacketSettings packet_settings(const CopySettings& s, const machine::Kinematics& kin) {
  PacketSettings ps = s.packets;
  ps.cone_middle = 0.5 * (s.visibility.cone_min + s.visibility.cone_max);
  ps.step = level_ground_spacing(s.finishing.tool.cutter, s.finishing.scallop);
  ps.feed = s.finishing_feed / 60;
  double acceleration = 1e300, jerk = 1e300;
  for (int j = 0; j < 3; ++j)
    acceleration = std::min(acceleration, kin.machine().axes[static_cast<std::size_t>(j)].acceleration),
    jerk = std::min(jerk, kin.machine().axes[static_cast<std::size_t>(j)].jerk);
  // A jerk-limited stop from the feed: v / A + A / J, or 2 sqrt(v / J) where A is never reached.
  const double stop = ps.feed > acceleration * acceleration / jerk ? ps.feed / acceleration + acceleration / jerk : 2 * std::sqrt(ps.feed / jerk);
  ps.turn = 2 * stop;
  ps.cell = std::max(1.0, 2 * s.normals.grid_step);
  return ps;
}

// Stage 4: packets; a leftover joins a packet whose direction reaches it with the whole window.
void choose_packets(const geometry::PointCloud& cloud, const std::vector<Eigen::Vector3d>& collision, const std::vector<char>& blocked, const CopySettings& s,
                    const machine::Kinematics& kin, CopyResult& out, const Say& say) {
  std::map<int, std::unique_ptr<BodyCheck>> bodies;
  std::mutex body_lock;
  // Leftovers whose cutter would enter an obstacle (`blocked`, from the visibility) are re-attached to
  // no packet either.
  const auto reaches = [&](int i, int j) {
    const Eigen::Vector3d& d = out.visibility.directions.unit[static_cast<std::size_t>(j)];
    if (d.dot(out.row_normals[static_cast<std::size_t>(i)]) < 0) return false;
    const BodyCheck* body = nullptr;
    {
      std::lock_guard guard(body_lock);
      auto& slot = bodies[j];
      if (!slot) slot = std::make_unique<BodyCheck>(collision, d, s.finishing.tool, s.visibility.graze);
      body = slot.get();
    }
    return blocked.empty() || !blocked[static_cast<std::size_t>(i)] ? body->clear(out.row_points[static_cast<std::size_t>(i)], out.row_normals[static_cast<std::size_t>(i)])
                                                                      : false;
  };
  const PacketSettings ps = packet_settings(s, kin);
  out.packets = group_packets(out.visibility, out.row_points, out.row_normals, ps, reaches);
  if (out.packets.directions.empty()) throw InputError(cloud.origin + ": no direction the machine reaches sees any point of the cloud (" + out.packets.method + ")");
  say("packets: " + std::to_string(out.packets.directions.size()) + " (" + out.packets.method + "), " + std::to_string(out.packets.covered) + " of " +
      std::to_string(out.row_points.size()) + " points covered");
}

// The drop's bin cell: about 24 points a cell where the cloud is dense (a drop reads the few cells
// its bound cannot rule out, and reads them whole), never over half the cutter's radius nor under a
// quarter of a millimetre. A speed knob only: the drop is the same whatever the cell.
double drop_cell(std::span<const Eigen::Vector3d> points, double radius) {
  const geometry::Box3 box = geometry::bounding_box(points);
  const double area = std::max(1.0, (box.hi.x() - box.lo.x()) * (box.hi.y() - box.lo.y()));
  const double density = static_cast<double>(points.size()) / area;  // a lower bound in any frame's XY
  return std::clamp(std::sqrt(24 / std::max(density, 1e-9)), 0.25, std::max(0.25, radius / 2));
}

// What stage 5 plans each packet against.
struct PacketInputs {
  const std::vector<Eigen::Vector3d>& collision;  // the scan first, then the side and the obstacles
  std::size_t scan_points;
  const PacketSettings& packets;                  // the floor's step, feed, turn and cell
  const geometry::CloudVoxelMap* map;  // roughing's, when it is on
  const CopySettings& settings;
  const machine::Kinematics& kin;
};

// Stage 5, one packet: its drop frame, roughing, finishing, programs and checks.
PacketPlan plan_packet(std::size_t k, int points, const CopyResult& out, const PacketInputs& in, Stopwatch& watch, const Say& say) {
  const CopySettings& s = in.settings;
  PacketPlan plan;
  plan.direction = out.packets.directions[k];
  plan.axis = out.visibility.directions.unit[static_cast<std::size_t>(plan.direction)];
  plan.rotary = out.visibility.rotary[static_cast<std::size_t>(plan.direction)];
  plan.frame = geometry::frame_along(plan.axis);
  plan.points = points;
  std::vector<Eigen::Vector3d> mine;
  std::vector<int> members;
  for (std::size_t i = 0; i < out.row_points.size(); ++i)
    if (out.packets.packet_of[i] == static_cast<int>(k)) mine.push_back(plan.frame * out.row_points[i]), members.push_back(static_cast<int>(i));
  plan.floor = finishing_floor(out.row_points, out.row_normals, members, plan.frame, in.packets.step, in.packets.feed, in.packets.turn, in.packets.cell);
  const geometry::CloudBins bins(geometry::rotated(in.collision, plan.frame), drop_cell(in.collision, s.finishing.tool.cutter.radius));
  watch.add_to("finishing");
  const std::string name = "packet " + std::to_string(k + 1);
  say(name + ": axis (" + std::to_string(plan.axis.x()).substr(0, 6) + ", " + std::to_string(plan.axis.y()).substr(0, 6) + ", " + std::to_string(plan.axis.z()).substr(0, 6) +
      "), " + std::to_string(plan.points) + " points");
  if (mine.empty()) {
    plan.error = "no point";
    return plan;
  }
  if (s.rough) {
    const CloudArea area(mine, s.roughing.longitudinal_step, s.roughing.tool.cutter.radius + s.stock_margin);
    double bottom = 1e300;
    for (const auto& p : mine) bottom = std::min(bottom, p.z());
    plan.roughing = plan_cloud_roughing(*in.map, plan.frame, out.stock, area, bottom, s.roughing);
    // The program (post-processing and feed prediction, one thread) and the whole-tool check (many)
    // read the same path: side by side.
    tbb::parallel_invoke([&] { make_program(plan.rough_op, plan.roughing->path, plan.frame, s.roughing_feed, name + " roughing", s.roughing_tool_number,
                                               s.roughing.tool.cutter.radius, s, in.kin); },
                         [&] { plan.rough_op.check = check_path(bins, plan.roughing->path, s.roughing.tool, s.roughing.tool.cutter.radius / 4, 0); });
    refuse_if_over(plan.rough_op, plan.frame, 0);
    watch.add_to("roughing");
  }
  try {
    const CloudArea area(mine, std::max(s.finishing.longitudinal_step, s.normals.grid_step), s.finishing.tool.cutter.radius);
    CloudFinishingSettings finishing = s.finishing;
    finishing.scan_points = static_cast<int>(in.scan_points);
    finishing.noise = out.noise;
    plan.finishing = plan_cloud_finishing(bins, area, finishing);
    tbb::parallel_invoke([&] { make_program(plan.finish_op, plan.finishing->path, plan.frame, s.finishing_feed, name + " finishing", s.program.tool,
                                               s.finishing.tool.cutter.radius, s, in.kin); },
                         [&] {
                           plan.finish_op.check =
                               check_path(bins, plan.finishing->path, s.finishing.tool, std::max(0.05, s.finishing.longitudinal_step / 2), s.finishing.chord_tolerance);
                         });
    refuse_if_over(plan.finish_op, plan.frame, s.finishing.chord_tolerance);
  } catch (const InputError& e) {
    plan.error = e.what();
  }
  watch.add_to("finishing");
  return plan;
}

}  // namespace

CopyResult copy_cloud(const geometry::PointCloud& cloud, const CopySettings& s, const machine::Kinematics& kin, const std::function<void(const std::string&)>& progress) {
  const Say say = [&](const std::string& line) {
    if (progress) progress(line);
  };
  CopyResult out;
  Stopwatch watch(out.times);
  out.cloud_points = cloud.size();
  out.cloud_box = geometry::bounding_box(cloud.points);
  out.base_top = s.stock_base_top.value_or(out.cloud_box.lo.z());
  if (s.stock_lo) {
    out.stock.lo = *s.stock_lo, out.stock.hi = *s.stock_hi;
  } else {
    out.stock.lo = out.cloud_box.lo - Eigen::Vector3d::Constant(s.stock_margin), out.stock.hi = out.cloud_box.hi + Eigen::Vector3d::Constant(s.stock_margin);
    out.stock.lo.z() = std::min(out.cloud_box.lo.z(), out.base_top) - s.stock_margin;  // the base under a sheet that stands above it
  }
  out.obstacle_spacing = obstacle_spacing(s);
  out.hole_radius = hole_radius(s);
  const geometry::ScanSurvey survey(cloud.points);
  out.spacing = survey.spacing, out.spacing_p90 = survey.spacing_p90;
  out.noise = geometry::scan_noise(cloud.points, survey.tree);
  const std::vector<Eigen::Vector3d> sides = find_sides(cloud, survey, s, out, say);
  watch.stage("rim");
  complete(cloud, survey, s, out, say);
  watch.stage("completion");
  find_normals(cloud, sides, s, out, say);
  watch.stage("normals");
  const std::vector<Eigen::Vector3d> collision = collision_points(cloud, out.completion, sides, s, out);
  // The visibility matrix's body tests read the collision set thinned to a point per quarter-millimetre
  // cube: they rank the directions, and the paths, always dropped on every point, keep the tool out of
  // whatever a thinned point stood for. A leftover point is re-attached by a test on every point.
  const std::vector<Eigen::Vector3d> thinned = geometry::thinned(collision, 0.25);
  const std::size_t obstacles_from = cloud.size() + out.completion.size();
  const std::vector<char> blocked = compute_visibility(thinned, std::span<const Eigen::Vector3d>(collision).subspan(obstacles_from), s, kin, out, say);
  watch.stage("visibility");
  choose_packets(cloud, collision, blocked, s, kin, out, say);
  watch.stage("packets");
  std::optional<geometry::CloudVoxelMap> map;
  if (s.rough) map.emplace(collision, roughing_voxel(s.roughing));  // the obstacles too: roughing must not enter the base or a fixture
  watch.add_to("roughing");
  const std::vector<int> sizes = out.packets.sizes();
  const PacketSettings floor_settings = packet_settings(s, kin);
  for (std::size_t k = 0; k < out.packets.directions.size(); ++k)
    out.plans.push_back(plan_packet(k, sizes[k], out, {collision, cloud.size() + out.completion.size(), floor_settings, map ? &*map : nullptr, s, kin}, watch, say));
  return out;
}

}  // namespace drom::paths
