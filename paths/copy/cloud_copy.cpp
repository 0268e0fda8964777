#include "paths/copy/cloud_copy.hpp"

#include "geometry/cloud_bins.hpp"
#include "geometry/cloud_voxel_map.hpp"
#include "machine/feed_prediction.hpp"
#include "machine/post_processor.hpp"
#include "paths/copy/pca_normals.hpp"
#include "support/input_error.hpp"
#include "support/resources.hpp"

#include <tbb/parallel_invoke.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <map>
#include <memory>
#include <mutex>
#include <numbers>
#include <sstream>

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

using Say = std::function<void(const std::string&)>;

// Stage 1: normals, the cloud's own or by sphere launching (and the PCA estimate beside them).
void find_normals(const geometry::PointCloud& cloud, const CopySettings& s, CopyResult& out, const Say& say) {
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
  out.normals = launch_spheres(cloud.points, s.normals);
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
std::vector<Eigen::Vector3d> collision_points(const geometry::PointCloud& cloud, const CopySettings& s, CopyResult& out) {
  geometry::Box3 stock;
  if (s.stock_lo) stock.lo = *s.stock_lo, stock.hi = *s.stock_hi;
  else stock.lo = out.cloud_box.lo - Eigen::Vector3d::Constant(s.stock_margin), stock.hi = out.cloud_box.hi + Eigen::Vector3d::Constant(s.stock_margin);
  out.stock = stock;
  std::vector<Obstacle> obstacles = s.fixtures;
  if (s.stock_base_is_obstacle && stock.lo.z() < out.cloud_box.lo.z() - 1e-9) {
    Obstacle base;
    base.name = "stock base";
    base.lo = stock.lo, base.hi = Eigen::Vector3d(stock.hi.x(), stock.hi.y(), out.cloud_box.lo.z());
    obstacles.push_back(base);
  }
  std::vector<Eigen::Vector3d> collision = cloud.points;
  const double spacing = std::min(s.finishing.tool.cutter.radius, s.roughing.tool.cutter.radius) / 3;
  for (const auto& o : obstacles) {
    const auto surface = obstacle_surface(o, spacing);
    collision.insert(collision.end(), surface.begin(), surface.end());
  }
  out.obstacle_points = collision.size() - cloud.size();
  return collision;
}

// Stage 3: which directions the machine reaches see each point with the whole tool.
void compute_visibility(const std::vector<Eigen::Vector3d>& collision, const CopySettings& s, const machine::Kinematics& kin, CopyResult& out, const Say& say) {
  say("visibility: " + std::to_string(out.row_points.size()) + " points x the (" + std::to_string(static_cast<int>(s.visibility.phi_step)) + ", " +
      std::to_string(static_cast<int>(s.visibility.theta_step)) + ") degree grid");
  VisibilitySettings vis = s.visibility;
  vis.tool = s.finishing.tool;
  vis.machine = &kin;
  out.visibility = visibility_matrix(collision, out.row_points, out.row_normals, vis);
}

// Stage 4: packets; a leftover joins a packet whose direction reaches it with the whole window.
void choose_packets(const geometry::PointCloud& cloud, const std::vector<Eigen::Vector3d>& collision, const CopySettings& s, CopyResult& out, const Say& say) {
  std::map<int, std::unique_ptr<BodyCheck>> bodies;
  std::mutex body_lock;
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
    return body->clear(out.row_points[static_cast<std::size_t>(i)], out.row_normals[static_cast<std::size_t>(i)]);
  };
  PacketSettings ps = s.packets;
  ps.cone_middle = 0.5 * (s.visibility.cone_min + s.visibility.cone_max);
  out.packets = group_packets(out.visibility, out.row_points, out.row_normals, ps, reaches);
  if (out.packets.directions.empty()) throw InputError(cloud.origin + ": no direction the machine reaches sees any point of the cloud (" + out.packets.method + ")");
  say("packets: " + std::to_string(out.packets.directions.size()) + " (" + out.packets.method + "), " + std::to_string(out.packets.covered) + " of " +
      std::to_string(out.row_points.size()) + " points covered");
}

// What stage 5 plans each packet against.
struct PacketInputs {
  const std::vector<Eigen::Vector3d>& collision;
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
  for (std::size_t i = 0; i < out.row_points.size(); ++i)
    if (out.packets.packet_of[i] == static_cast<int>(k)) mine.push_back(plan.frame * out.row_points[i]);
  const geometry::CloudBins bins(geometry::rotated(in.collision, plan.frame), std::max(0.25, s.finishing.tool.cutter.radius / 2));
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
    watch.add_to("roughing");
  }
  try {
    const CloudArea area(mine, std::max(s.finishing.longitudinal_step, s.normals.grid_step), s.finishing.tool.cutter.radius);
    plan.finishing = plan_cloud_finishing(bins, area, s.finishing);
    tbb::parallel_invoke([&] { make_program(plan.finish_op, plan.finishing->path, plan.frame, s.finishing_feed, name + " finishing", s.program.tool,
                                               s.finishing.tool.cutter.radius, s, in.kin); },
                         [&] {
                           plan.finish_op.check =
                               check_path(bins, plan.finishing->path, s.finishing.tool, std::max(0.05, s.finishing.longitudinal_step / 2), s.finishing.chord_tolerance);
                         });
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
  find_normals(cloud, s, out, say);
  watch.stage("normals");
  const std::vector<Eigen::Vector3d> collision = collision_points(cloud, s, out);
  compute_visibility(collision, s, kin, out, say);
  watch.stage("visibility");
  choose_packets(cloud, collision, s, out, say);
  watch.stage("packets");
  std::optional<geometry::CloudVoxelMap> map;
  if (s.rough) map.emplace(collision, roughing_voxel(s.roughing));  // the obstacles too: roughing must not enter the base or a fixture
  watch.add_to("roughing");
  const std::vector<int> sizes = out.packets.sizes();
  for (std::size_t k = 0; k < out.packets.directions.size(); ++k)
    out.plans.push_back(plan_packet(k, sizes[k], out, {collision, map ? &*map : nullptr, s, kin}, watch, say));
  return out;
}

}  // namespace drom::paths
