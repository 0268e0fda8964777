#include "paths/copy/copy_run.hpp"

#include "geometry/cloud_outliers.hpp"
#include "geometry/cloud_reader.hpp"
#include "geometry/cloud_writer.hpp"
#include "machine/machine_definition.hpp"
#include "paths/copy/cloud_copy.hpp"
#include "support/atomic_file.hpp"
#include "support/run_folder.hpp"
#include "support/input_error.hpp"
#include "support/summary.hpp"
#include "support/toml_reader.hpp"
#include "support/vtk_fields.hpp"

#include <algorithm>
#include <cstdio>

namespace drom::paths {

namespace {

nlohmann::json vec(const Eigen::Vector3d& v) { return {v.x(), v.y(), v.z()}; }

// A path as polylines, one per run of moves of the same kind, in the part frame (q^T tip), with the
// motion (0 cut, 1 link, 2 rapid) and pass of each point.
void write_path_vtp(const std::filesystem::path& file, const CloudPath& path, const Eigen::Matrix3d& q) {
  Polylines p;
  p.points.resize(3, static_cast<Eigen::Index>(path.size()));
  std::vector<double> motion, pass;
  for (std::size_t i = 0; i < path.size(); ++i) {
    p.points.col(static_cast<Eigen::Index>(i)) = q.transpose() * path.tips[i];
    motion.push_back(static_cast<double>(path.motion[i] == Motion::cut ? 0 : path.motion[i] == Motion::link ? 1 : 2));
    pass.push_back(path.pass[i]);
  }
  // One polyline for the whole path: the order is the machining order.
  std::vector<long long> line(path.size());
  for (std::size_t i = 0; i < path.size(); ++i) line[i] = static_cast<long long>(i);
  if (!line.empty()) p.lines.push_back(line);
  p.fields.point_scalars = {{"motion", motion}, {"pass", pass}};
  write_polylines_vtp(file, p);
}

nlohmann::json check_json(const PathCheck& c, const Eigen::Matrix3d& frame) {
  return {{"positions", c.positions},
          {"deepest_mm", c.deepest},
          {"worst_tip_drop_frame", vec(c.worst)},
          {"worst_tip_part_frame", vec(frame.transpose() * c.worst)},
          {"positions_over_tolerance", c.over}};
}

// The rows: points with a normal, their packet, how many directions see them, overlap (PLY and VTP).
void write_point_files(const std::filesystem::path& out, const geometry::PointCloud& cloud, const CopyResult& r, std::vector<std::string>& files) {
  geometry::PointCloud rows;
  rows.origin = cloud.origin;
  rows.points = r.row_points, rows.normals = r.row_normals;
  const int n = static_cast<int>(rows.points.size());
  std::vector<double> packet(static_cast<std::size_t>(n)), seen(static_cast<std::size_t>(n), 0), overlap(static_cast<std::size_t>(n)), hits(static_cast<std::size_t>(n));
  for (int i = 0; i < n; ++i) {
    const auto k = static_cast<std::size_t>(i);
    packet[k] = r.packets.packet_of[k];
    overlap[k] = r.packets.overlap[k];
    hits[k] = r.normals.hits.empty() ? 0 : r.normals.hits[k];
    for (int j = 0; j < static_cast<int>(r.visibility.columns.size()); ++j) seen[k] += r.visibility.test(i, j);
  }
  geometry::write_ply(out / "normals.ply", rows, {{"packet", packet, true}, {"directions_seeing", seen, true}, {"overlap", overlap, true}, {"hits", hits, true}});
  files.push_back("normals.ply");
  // What drom assumed beyond the scan: the points that completed it, and the part's side below its rim.
  for (const auto& [name, points] : {std::pair{"completion.ply", &r.completion}, std::pair{"rim.ply", &r.rim.points}, std::pair{"side.ply", &r.side}}) {
    if (points->empty()) continue;
    geometry::PointCloud c;
    c.origin = cloud.origin;
    c.points = *points;
    geometry::write_ply(out / name, c);
    files.push_back(name);
  }
  Eigen::Matrix3Xd points(3, n);
  Eigen::VectorXd normals(3 * n);
  for (int i = 0; i < n; ++i) points.col(i) = rows.points[static_cast<std::size_t>(i)], normals.segment<3>(3 * i) = rows.normals[static_cast<std::size_t>(i)];
  VtuFields f;
  f.point_scalars = {{"packet", packet}, {"directions_seeing", seen}, {"overlap", overlap}};
  f.point_vectors = {{"normal", normals}};
  write_points_vtp(out / "packets.vtp", points, f);
  files.push_back("packets.vtp");
}

// One operation of a packet (roughing or finishing): its path (VTP), CL data and program written
// under packet_<k>/, and its figures.
nlohmann::json write_operation(const std::filesystem::path& out, const std::string& dir, const std::string& name, const PacketOperation& op,
                               const Eigen::Matrix3d& frame, std::vector<std::string>& files) {
  nlohmann::json e = {{"path_points", op.path.size()},
                      {"cutting_length_mm", op.path.cutting_length()},
                      {"rapid_length_mm", op.path.rapid_length()},
                      {"cycle_time_s", op.cycle_time},
                      {"check", check_json(op.check, frame)}};
  if (!op.path.empty()) {
    write_path_vtp(out / dir / (name + ".vtp"), op.path, frame);
    write_file_atomically(out / dir / (name + "_cl.csv"), machine::cl_csv(op.cl));
    files.push_back(dir + "/" + name + ".vtp"), files.push_back(dir + "/" + name + "_cl.csv");
  }
  if (!op.gcode.empty()) {
    write_file_atomically(out / dir / (name + ".ngc"), op.gcode);
    files.push_back(dir + "/" + name + ".ngc");
  }
  if (op.verdict) e["program_verdict"] = op.verdict->to_json();
  if (!op.error.empty()) e["refused"] = op.error;  // no program written: why
  return e;
}

// Packet k's files and figures.
nlohmann::json write_packet(const std::filesystem::path& out, std::size_t k, const PacketPlan& p, int points, std::vector<std::string>& files) {
  const std::string dir = "packet_" + std::to_string(k + 1);
  std::filesystem::create_directories(out / dir);
  nlohmann::json j = {{"direction", p.direction},
                      {"axis", vec(p.axis)},
                      {"tilt_deg", tilt_from_z(p.axis)},
                      {"rotary_deg", {p.rotary.x(), p.rotary.y()}},
                      {"points", points}};
  if (!p.error.empty()) j["error"] = p.error;
  if (p.finishing) {
    const CloudFinishing& f = *p.finishing;
    j["finishing"] = write_operation(out, dir, "finishing", p.finish_op, p.frame, files);
    j["finishing"].update({{"passes", f.passes},
                           {"nodes", f.nodes},
                           {"inserted_nodes", f.inserted},
                           {"unresolved_chords", f.unresolved},
                           {"unresolved_worst_mm", f.unresolved_worst},
                           {"gaps", f.gaps},
                           {"lifted_by_shank_or_holder", f.lifted},
                           {"transverse_step_mm", {{"smallest", f.smallest_step}, {"mean", f.mean_step}, {"largest", f.largest_step}}},
                           {"floor",
                            {{"area_mm2", p.floor.area},
                             {"length_mm", p.floor.length},
                             {"time_s", p.floor.time},
                             {"cutting_length_over_floor", p.floor.length > 0 ? p.finish_op.path.cutting_length() / p.floor.length : 0.0},
                             {"cycle_over_floor", p.floor.time > 0 ? p.finish_op.cycle_time / p.floor.time : 0.0}}}});
  }
  if (p.roughing) {
    const CloudRoughing& g = *p.roughing;
    j["roughing"] = write_operation(out, dir, "roughing", p.rough_op, p.frame, files);
    j["roughing"].update({{"layers", g.layers},
                          {"nodes", g.nodes},
                          {"cut", g.cut},
                          {"blocked", g.blocked},
                          {"unreachable", g.unreachable},
                          {"side_entries", g.side_entries},
                          {"ramps", g.ramps},
                          {"zigzag_ramps", g.zigzag_ramps},
                          {"voxels", g.voxels},
                          {"voxel_mm", g.voxel}});
  }
  return j;
}

nlohmann::json copy_summary(const CopyRunOptions& o, const CopySettings& s, const machine::Machine& m, const CopyResult& r, const nlohmann::json& packets,
                            const std::vector<std::string>& files) {
  nlohmann::json times = nlohmann::json::array();
  double wall = 0;
  for (const auto& t : r.times) times.push_back({{"stage", t.stage}, {"wall_s", t.wall}, {"cpu_s", t.cpu}}), wall += t.wall;
  return {{"command", "copy"},
          {"cloud", o.cloud.string()},
          {"settings", s.origin},
          {"machine", {{"name", m.name}, {"kinematics", machine::chain_name(m.chain)}}},
          {"cloud_points", r.cloud_points},
          {"obstacle_points", r.obstacle_points},
          {"stock", {{"lo", vec(r.stock.lo)}, {"hi", vec(r.stock.hi)}, {"base_top", r.base_top}}},
          {"rim",
           {{"side", s.rim_is_side ? "down to the base" : "open"},
            {"side_depth_mm", s.side_depth},
            {"rim_points", r.rim.points.size()},
            {"side_points", r.side_points},
            {"cell_mm", r.rim.cell},
            {"obstacle_spacing_mm", r.obstacle_spacing}}},
          {"normals", {{"from_file", r.normals_from_file}, {"points", r.row_points.size()}, {"pca_mean_disagreement_deg", r.pca_disagreement}}},
          {"visibility",
           {{"directions", r.visibility.columns.size()},
            {"reachable_directions", std::count(r.visibility.reachable.begin(), r.visibility.reachable.end(), 1)},
            {"tool_visible_bits", r.visibility.tool_visible},
            {"cleared_by_collision", r.visibility.collisions}}},
          {"grouping",
           {{"method", r.packets.method},
            {"packets", r.packets.directions.size()},
            {"covered", r.packets.covered},
            {"coverage", r.row_points.empty() ? 0.0 : static_cast<double>(r.packets.covered) / static_cast<double>(r.row_points.size())},
            {"coverage_met", r.packets.coverage_met},
            {"machinable", r.packets.machinable},
            {"decided_by", r.packets.decided_by},
            {"tied_sets", r.packets.tied},
            {"largest_tilt_deg", r.packets.largest_tilt},
            {"tilt_sum_deg", r.packets.tilt_sum},
            {"estimated_finishing_cycle_s", r.packets.estimated_cycle},
            {"overlap_points", r.packets.overlaps},
            {"reattached", r.packets.reattached},
            {"unmachinable", r.packets.unmachinable},
            {"combinations", r.packets.combinations}}},
          {"packets", packets},
          {"times", times},
          {"wall_s", wall},
          {"files", files},
          {"machine_info", machine_info()}};
}

}  // namespace

// The scan as the copy uses it: points that are not finite numbers and far outliers dropped and
// counted, or refused (cloud.bad_points = "error").
geometry::PointCloud read_scan(const CopyRunOptions& o, const CopySettings& s, geometry::FarOutliers& outliers) {
  geometry::PointCloud cloud = geometry::read_cloud(o.cloud, s.scale, {.not_finite_is_error = s.bad_points_are_errors});
  outliers = geometry::find_far_outliers(cloud);
  if (outliers.indices.empty()) return cloud;
  if (s.bad_points_are_errors) {
    const Eigen::Vector3d& p = cloud.points[outliers.indices.front()];
    char where[160];
    std::snprintf(where, sizeof where, "point (%.3f, %.3f, %.3f) mm", p.x(), p.y(), p.z());
    throw InputError(o.cloud.string() + ": " + where + " is a far outlier (" + std::to_string(outliers.indices.size()) +
                     " in all): no 8 other points within " + std::to_string(outliers.threshold_mm) + " mm, where the cloud's typical spacing is " +
                     std::to_string(outliers.median_mm) + " mm; cloud.bad_points = \"drop\" drops them");
  }
  geometry::remove_points(cloud, outliers.indices);
  cloud.dropped.far_outliers = outliers.indices.size();
  return cloud;
}

nlohmann::json scan_summary(const geometry::PointCloud& cloud, const geometry::FarOutliers& outliers, const CopyResult& r) {
  const auto& d = cloud.dropped;
  const auto share = [](std::size_t part, std::size_t whole) { return whole ? static_cast<double>(part) / static_cast<double>(whole) : 0.0; };
  return {{"points_read", cloud.size() + d.not_finite + d.far_outliers},
          {"points_kept", cloud.size()},
          {"dropped_not_finite", d.not_finite},
          {"first_not_finite", d.first_not_finite},
          {"dropped_far_outliers", d.far_outliers},
          {"outlier_threshold_mm", outliers.threshold_mm},
          {"typical_spacing_mm", outliers.median_mm},
          {"points_with_normal", r.row_points.size()},
          {"typical_spacing_mm", r.spacing > 0 ? r.spacing : r.rim.spacing},
          {"spacing_p90_mm", r.spacing_p90},
          {"noise_mm", r.noise},
          {"completion", {{"crease_points", r.crease_points}, {"crease_cells", r.crease_cells}, {"hole_points", r.hole_points}, {"hole_radius_mm", r.hole_radius}, {"noise_floor_points", r.noise_floor_points}, {"noise_floor_lift_deviations", r.noise_floor_deviations}}},
          {"coverage_of_points_kept", share(r.packets.covered, cloud.size())},
          {"coverage_of_points_with_normal", share(r.packets.covered, r.row_points.size())}};
}

nlohmann::json run_copy(const CopyRunOptions& o) {
  std::vector<std::string> overrides = o.overrides;
  if (!o.tool.empty()) overrides.push_back("finishing.tool=\"" + o.tool + "\"");
  if (!o.machine.empty()) overrides.push_back("machine.name=\"" + o.machine + "\"");
  const CopySettings s = o.settings ? read_copy_settings(read_input_file(*o.settings, "settings file"), o.settings->string(), overrides) : read_copy_settings("", "<defaults>", overrides);
  const machine::Machine m = machine::load_machine(s.machine, s.machine_overrides);
  const machine::Kinematics kinematics(m);
  geometry::FarOutliers outliers;
  const geometry::PointCloud cloud = read_scan(o, s, outliers);
  RunFolder folder(o.out, {.resume = false, .reused = {}, .inputs = {o.cloud, o.settings.value_or("")}});  // before the work: a folder that cannot be written is found now
  const auto progress = [&](const std::string& line) {
    if (!o.quiet) std::printf("  %s\n", line.c_str()), std::fflush(stdout);
  };
  if (cloud.dropped.not_finite + cloud.dropped.far_outliers > 0)
    progress("scan: " + std::to_string(cloud.size()) + " points kept; dropped " + std::to_string(cloud.dropped.not_finite) + " not finite" +
             (cloud.dropped.not_finite ? " (first: " + cloud.dropped.first_not_finite + ")" : std::string()) + " and " + std::to_string(cloud.dropped.far_outliers) +
             " far outliers (no 8 neighbours within " + std::to_string(outliers.threshold_mm) + " mm)");
  const CopyResult r = copy_cloud(cloud, s, kinematics, progress);

  const std::filesystem::path& out = folder.staging();
  std::vector<std::string> files;
  write_point_files(out, cloud, r, files);
  nlohmann::json packets = nlohmann::json::array();
  const auto sizes = r.packets.sizes();
  for (std::size_t k = 0; k < r.plans.size(); ++k) packets.push_back(write_packet(out, k, r.plans[k], sizes[k], files));
  nlohmann::json summary = copy_summary(o, s, m, r, packets, files);
  summary["scan"] = scan_summary(cloud, outliers, r);
  write_summary(out, summary);
  folder.commit();
  return summary;
}

}  // namespace drom::paths
