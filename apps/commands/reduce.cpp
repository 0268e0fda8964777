// drom reduce: the offline database -> the light model the online predictor loads (design.md §5).
//   1. read database.h5 (an offline run: one column per unit profile) and the case stored in it;
//   2. the target surface's faces and the final part's surface, from the database's mesh;
//   3. the programmed path (tool tip, program time) and, per target node, when the tool cut it;
//   4. POD + space-time compression (reduce/model_reduction.hpp), written atomically as an HDF5 model;
//   5. VTK of the modes (one standard deviation of the prior each), for ParaView;
//   6. summary.json: rank, bounds, measured max error against the database, sizes.
#include "apps/case_file.hpp"
#include "apps/case_setup.hpp"
#include "apps/commands.hpp"
#include "apps/summary.hpp"
#include "fem/node_sets.hpp"
#include "fem/vtk_output.hpp"
#include "levelset/toolpath.hpp"
#include "reduce/cut_time.hpp"
#include "reduce/model_reduction.hpp"
#include "apps/database_matrix.hpp"
#include "support/hdf5_reader.hpp"
#include "support/input_error.hpp"
#include "support/png_plot.hpp"
#include "support/atomic_file.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <limits>
#include <map>

namespace drom::app {

namespace {

fem::Mesh read_mesh(const Hdf5Reader& h5, const std::filesystem::path& file) {
  fem::Mesh mesh;
  const std::string element = h5.text_attribute("element");
  if (element == "hex20") mesh.type = fem::ElementType::Hex20;
  else if (element == "hex27") mesh.type = fem::ElementType::Hex27;
  else if (element == "tet10") mesh.type = fem::ElementType::Tet10;
  else throw InputError(file.string() + ": attribute element: expected hex20, hex27 or tet10, got '" + element + "'");
  const Eigen::MatrixXd xyz = read_matrix(h5, "node_coordinates"), conn = read_matrix(h5, "connectivity");
  if (xyz.cols() != 3 || conn.cols() != fem::nodes_per_element(mesh.type))
    throw InputError(file.string() + ": node_coordinates / connectivity do not match a " + element + " mesh");
  for (Eigen::Index n = 0; n < xyz.rows(); ++n) mesh.nodes.emplace_back(xyz.row(n).transpose());
  for (Eigen::Index e = 0; e < conn.rows(); ++e)
    for (Eigen::Index k = 0; k < conn.cols(); ++k) {
      const double v = conn(e, k);
      if (!(v >= 0 && v < static_cast<double>(xyz.rows()))) throw InputError(file.string() + ": connectivity row " + std::to_string(e) + " names a node that does not exist");
      mesh.connectivity.push_back(static_cast<int>(v));
    }
  return mesh;
}

// Faces as rows of local indices into `nodes` (global -> local through `local`).
std::vector<int> local_faces(const std::vector<fem::BoundaryFace>& faces, const std::map<int, int>& local) {
  std::vector<int> out;
  for (const auto& f : faces)
    for (int n : f.nodes) out.push_back(local.at(n));
  return out;
}

// The programmed path as a polyline of tool-tip positions with their program times, and whether each
// segment (i, i + 1) belongs to a cutting move.
Eigen::MatrixXd path_waypoints(const levelset::Toolpath& path, const levelset::PathTimeline& timeline, std::vector<char>& cutting) {
  std::vector<Eigen::Vector4d> rows;
  cutting.clear();
  for (std::size_t m = 0; m < path.moves.size(); ++m) {
    const auto& move = path.moves[m];
    const auto points = levelset::move_polyline(move, 0.01);
    double along = 0;
    for (std::size_t k = 0; k < points.size(); ++k) {
      if (k > 0) along += (points[k] - points[k - 1]).norm();
      if (k == 0 && !rows.empty()) continue;  // the previous move's end
      const double t = timeline.time_at_length(timeline.move_start_length(m) + std::min(along, move.length()));
      if (!rows.empty()) cutting.push_back(move.cutting());
      rows.emplace_back(points[k].x(), points[k].y(), points[k].z(), t);
    }
  }
  cutting.push_back(0);  // past the last waypoint
  Eigen::MatrixXd w(static_cast<Eigen::Index>(rows.size()), 4);
  for (std::size_t i = 0; i < rows.size(); ++i) w.row(static_cast<Eigen::Index>(i)) = rows[i].transpose();
  return w;
}

// The surface on these mesh nodes (in this order): its faces are the element faces with every node
// among them. `what` names it in errors.
reduce::SurfaceMesh surface_on(const fem::Mesh& mesh, const std::vector<int>& nodes, const std::string& what, const std::filesystem::path& file) {
  std::map<int, int> local;
  Eigen::Matrix3Xd xyz(3, static_cast<Eigen::Index>(nodes.size()));
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    if (nodes[i] < 0 || nodes[i] >= mesh.node_count()) throw InputError(file.string() + ": " + what + " names a node that does not exist");
    local[nodes[i]] = static_cast<int>(i);
    xyz.col(static_cast<Eigen::Index>(i)) = mesh.nodes[static_cast<std::size_t>(nodes[i])];
  }
  const auto faces = fem::faces_within(mesh, nodes);
  if (faces.empty()) throw InputError(file.string() + ": no element face lies on the " + what);
  return reduce::SurfaceMesh(xyz, local_faces(faces, local), static_cast<int>(faces.front().nodes.size()));
}

}  // namespace

int reduce_command(const CommandOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  auto elapsed = [&] { return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(); };
  if (!options.case_path) throw InputError("drom reduce needs a database: drom reduce OUT/database.h5 --tol MM --out MODEL.h5");
  const std::filesystem::path db_path = *options.case_path;
  const std::filesystem::path model_path = options.out.extension() == ".h5" ? options.out : options.out / "model.h5";
  const std::filesystem::path out_dir = model_path.has_parent_path() ? model_path.parent_path() : std::filesystem::path(".");
  std::filesystem::create_directories(out_dir);

  // 1. The database and its case.
  const Hdf5Reader h5(db_path);
  if (h5.text_attribute("kind") != "offline")
    throw InputError(db_path.string() + ": a '" + h5.text_attribute("kind") + "' database; reduce needs an offline one (one column per unit profile)");
  const Case c = case_from_text(h5.text_attribute("case"), db_path.string());
  reduce::SnapshotDatabase db;
  db.B1 = read_matrix(h5, "B1");
  db.station_times = read_matrix(h5, "station_time");
  const Eigen::MatrixXd B2 = read_matrix(h5, "B2");
  const Eigen::MatrixXd target_ids = read_matrix(h5, "target_nodes"), activity = read_matrix(h5, "final_activity");
  const fem::Mesh mesh = read_mesh(h5, db_path);
  const auto nt = static_cast<std::size_t>(target_ids.rows());
  if (nt == 0 || db.B1.rows() != static_cast<Eigen::Index>(nt) * db.station_times.size())
    throw InputError(db_path.string() + ": B1 has " + std::to_string(db.B1.rows()) + " rows, expected stations x target nodes");
  if (B2.rows() != mesh.dof_count() || B2.cols() != db.B1.cols()) throw InputError(db_path.string() + ": B2 is not (3 x nodes) x profiles");
  if (!db.B1.allFinite() || !B2.allFinite()) throw InputError(db_path.string() + ": B1 or B2 holds NaN or infinite values");
  if (activity.rows() != mesh.element_count()) throw InputError(db_path.string() + ": final_activity has one value per element expected");

  // 2. Surfaces: the target (faces on the target nodes) and the final part (boundary of what is left).
  reduce::LightModel model;
  std::vector<int> target(nt);
  for (std::size_t i = 0; i < nt; ++i) target[i] = static_cast<int>(target_ids(static_cast<Eigen::Index>(i), 0));
  model.target = surface_on(mesh, target, "target surface (target_nodes)", db_path);
  const Eigen::Matrix3Xd& target_xyz = model.target.nodes();
  fem::Mesh kept = mesh;
  kept.connectivity.clear();
  for (int e = 0; e < mesh.element_count(); ++e)
    if (activity(e, 0) > 1e-3) kept.connectivity.insert(kept.connectivity.end(), mesh.element(e).begin(), mesh.element(e).end());
  const auto shape_faces = fem::boundary_faces(kept);
  std::map<int, int> shape_local;
  for (const auto& f : shape_faces)
    for (int n : f.nodes) shape_local.emplace(n, 0);
  model.shape_nodes.resize(3, static_cast<Eigen::Index>(shape_local.size()));
  db.final_shape.resize(3 * static_cast<Eigen::Index>(shape_local.size()), B2.cols());
  int next = 0;
  for (auto& [node, index] : shape_local) {
    index = next++;
    model.shape_nodes.col(index) = mesh.nodes[static_cast<std::size_t>(node)];
    db.final_shape.middleRows(3 * index, 3) = B2.middleRows(3 * node, 3);
  }
  model.shape_faces = local_faces(shape_faces, shape_local);
  model.shape_face_nodes = static_cast<int>(shape_faces.front().nodes.size());
  // The stock's top within --top-margin of the pocket, when asked for.
  std::vector<int> top;
  const PartModel part = build_part(c);
  if (options.top_margin >= 0) {
    if (!h5.has("B1_top")) throw InputError(db_path.string() + ": no B1_top (written before drom offline kept the stock's top); run drom offline again for --top-margin");
    const Eigen::MatrixXd B1_top = read_matrix(h5, "B1_top"), top_ids = read_matrix(h5, "top_nodes");
    const Eigen::Index ntop = top_ids.rows(), ns = db.station_times.size();
    if (ntop == 0 || B1_top.rows() != ntop * ns || B1_top.cols() != db.B1.cols())
      throw InputError(db_path.string() + ": B1_top has " + std::to_string(B1_top.rows()) + " rows, expected stations x top nodes");
    if (!B1_top.allFinite()) throw InputError(db_path.string() + ": B1_top holds NaN or infinite values");
    // The top within the margin of the pocket's footprint (in the part's own surface coordinates).
    std::vector<Eigen::Index> rows;
    for (Eigen::Index i = 0; i < ntop; ++i) {
      const int node = static_cast<int>(top_ids(i, 0));
      if (node < 0 || node >= mesh.node_count()) throw InputError(db_path.string() + ": top_nodes names a node that does not exist");
      const Eigen::Vector3d uvt = part.shape.to_parametric(mesh.nodes[static_cast<std::size_t>(node)]);
      const double m = options.top_margin + 1e-9;
      if (uvt.x() < c.pocket_x - m || uvt.x() > c.pocket_x + c.pocket_length_x + m || uvt.y() < c.pocket_y - m || uvt.y() > c.pocket_y + c.pocket_length_y + m) continue;
      top.push_back(node);
      rows.push_back(i);
    }
    const auto kept_top = static_cast<Eigen::Index>(top.size());
    db.B1_top.resize(kept_top * ns, B1_top.cols());
    for (Eigen::Index j = 0; j < kept_top; ++j)
      for (Eigen::Index s = 0; s < ns; ++s) db.B1_top.row(s * kept_top + j) = B1_top.row(s * ntop + rows[static_cast<std::size_t>(j)]);
    model.top = surface_on(mesh, top, "stock's top within --top-margin of the pocket", db_path);
  }

  // 3. Path, tool, and when each target node was cut.
  const levelset::Toolpath toolpath = build_toolpath(c, part);
  const levelset::PathTimeline timeline(toolpath);
  std::vector<char> cutting;
  model.path = path_waypoints(toolpath, timeline, cutting);
  const levelset::Tool tool = build_tool(c);
  model.tool_shape = c.tool_kind == "ball" ? reduce::ToolShape::Ball : reduce::ToolShape::Flat;
  model.tool_radius = tool.radius;
  model.pocket_depth = c.pocket_depth;
  model.target_cut_time.resize(static_cast<Eigen::Index>(nt));
  const double z_tolerance = 0.02 * c.pocket_depth;
  for (std::size_t i = 0; i < nt; ++i)
    model.target_cut_time[static_cast<Eigen::Index>(i)] = reduce::first_cover_time(model.path, cutting, target_xyz.col(static_cast<Eigen::Index>(i)), tool.radius, z_tolerance);
  // A top node is gone once the tool has been down to the floor under it.
  model.top_cut_time.resize(static_cast<Eigen::Index>(top.size()));
  for (std::size_t i = 0; i < top.size(); ++i)
    model.top_cut_time[static_cast<Eigen::Index>(i)] =
        reduce::first_cover_time(model.path, cutting, model.top.nodes().col(static_cast<Eigen::Index>(i)) - Eigen::Vector3d(0, 0, c.pocket_depth), tool.radius, z_tolerance);
  db.top_cut_time = model.top_cut_time;
  db.program_start = 0;

  // 4. Reduction.
  reduce::ReductionSettings settings;
  settings.tolerance = options.tolerance;
  settings.history_tolerance = options.history_tolerance >= 0 ? options.history_tolerance : 0.5 * options.tolerance;
  // The case's coefficients in the database's column order (sigma11's, then sigma22's), when they are
  // its columns' profile.
  Eigen::VectorXd case_coefficients(static_cast<Eigen::Index>(c.sigma11.size() + c.sigma22.size()));
  std::copy(c.sigma11.begin(), c.sigma11.end(), case_coefficients.begin());
  std::copy(c.sigma22.begin(), c.sigma22.end(), case_coefficients.begin() + static_cast<Eigen::Index>(c.sigma11.size()));
  const bool case_columns = !c.sigma11.empty() && case_coefficients.size() == db.B1.cols();
  const double largest = case_coefficients.size() > 0 ? case_coefficients.cwiseAbs().maxCoeff() : 0.0;
  settings.profile_scale = options.profile_scale > 0 ? options.profile_scale : (largest > 0 ? largest : 50.0);
  settings.max_rank = options.max_rank;
  // The prior: each unit profile's coefficient at the case's own magnitude for that direction and
  // degree (a rolled plate's stresses fall with the degree), floored at a tenth of the largest.
  if (options.profile_scale <= 0 && case_columns) settings.profile_sd = case_coefficients.cwiseAbs().cwiseMax(0.1 * settings.profile_scale);
  // The prior's mean: the case's own profile, the one the stock is expected to carry (a quenched
  // plate's skins are in compression, not as likely in tension: a zero mean would say they are).
  if (options.prior_mean == "case" && case_columns) settings.profile_mean = case_coefficients;
  const auto report = reduce::reduce_snapshots(db, settings, model);
  model.case_toml = h5.text_attribute("case");
  model.database_hash = h5.text_attribute("content_hash");
  model.write(model_path);

  // 5. Pictures: the target surface with each basis history at the last station and the cut times,
  //    and the final part's surface with each final-shape mode (warp by vector in ParaView).
  {
    fem::VtuFields target_fields, shape_fields;
    std::vector<double> cut(model.target_cut_time.data(), model.target_cut_time.data() + model.target_cut_time.size());
    for (double& t : cut)
      if (!std::isfinite(t)) t = -1;
    target_fields.point_scalars.emplace_back("cut_time_s", cut);
    const double t_end = db.station_times[db.station_times.size() - 1];
    for (int k = 0; k < model.rank(); ++k) {
      const Eigen::VectorXd u = model.histories[static_cast<std::size_t>(k)].at(t_end) * model.prior_sd[k];
      target_fields.point_scalars.emplace_back("U1_" + std::to_string(k + 1) + "_end_mm", std::vector<double>(u.data(), u.data() + u.size()));
      shape_fields.point_vectors.emplace_back("U2_" + std::to_string(k + 1) + "_mm", model.final_basis.col(k) * model.prior_sd[k]);
    }
    fem::write_surface_vtu(out_dir / "target_modes.vtu", model.target.nodes(), model.target.faces(), model.target.nodes_per_face(), target_fields);
    fem::write_surface_vtu(out_dir / "final_shape_modes.vtu", model.shape_nodes, model.shape_faces, model.shape_face_nodes, shape_fields);
  }

  // The singular values against the tolerance: where the POD stopped, and why.
  {
    std::string csv = "i,singular_value_mm,bound_if_truncated_here_mm,kept\n";
    PlotSeries values{"singular value", {}, {}, "o-"}, bounds{"bound if truncated after i", {}, {}, "s--"};
    for (Eigen::Index i = 0; i < model.singular_values.size(); ++i) {
      const double bound = reduce::max_norm_bound(model.singular_values, static_cast<int>(i + 1));
      char line[128];
      std::snprintf(line, sizeof line, "%ld,%.9e,%.9e,%d\n", static_cast<long>(i + 1), model.singular_values[i], bound, i < model.rank() ? 1 : 0);
      csv += line;
      values.x.push_back(static_cast<double>(i + 1)), values.y.push_back(model.singular_values[i]);
      bounds.x.push_back(static_cast<double>(i + 1)), bounds.y.push_back(bound > 0 ? bound : std::nan(""));
    }
    write_file_atomically(out_dir / "singular_values.csv", csv);
    PlotSpec plot;
    plot.title = "POD of B1 (" + c.name + "): r = " + std::to_string(model.rank());
    plot.x_label = "mode i";
    plot.y_label = "mm (plausible profile)";
    plot.series = {values, bounds};
    plot.hlines = {{"tolerance", settings.tolerance}};
    plot.log_y = true;
    write_png_plot(out_dir / "singular_values.png", plot);
  }

  // 6. Summary.
  const double model_mb = static_cast<double>(std::filesystem::file_size(model_path)) / 1048576.0;
  const double db_mb = static_cast<double>(std::filesystem::file_size(db_path)) / 1048576.0;
  std::size_t never_cut = 0;
  for (double t : model.target_cut_time) never_cut += !std::isfinite(t);
  std::vector<double> sigma(model.singular_values.data(), model.singular_values.data() + model.singular_values.size());
  write_summary(out_dir, {{"command", "reduce"},
                          {"case", c.name},
                          {"database", db_path.string()},
                          {"database_hash", model.database_hash},
                          {"model", model_path.filename().string()},
                          {"rank", model.rank()},
                          {"prior", model.prior_covariance.size() > 0 ? "each unit profile at the case's own coefficient magnitude (full covariance)"
                                                                      : "every unit profile at profile_scale (diagonal)"},
                          {"prior_mean", model.prior_mean.size() > 0 ? "the case's [stress] profile" : "zero"},
                          {"profiles", db.B1.cols()},
                          {"profile_scale_mpa", settings.profile_scale},
                          {"tolerance_mm", settings.tolerance},
                          {"history_tolerance_mm", settings.history_tolerance},
                          {"pod_max_bound_mm", model.pod_max_bound},
                          {"pod_euclidean_bound_mm", model.pod_euclidean_bound},
                          {"history_bound_mm", model.history_bound},
                          {"error_bound_mm", model.error_bound()},
                          {"measured_max_error_mm", report.measured_max_error},
                          {"history_terms", report.history_terms},
                          {"singular_values_mm", sigma},
                          {"target_nodes", nt},
                          {"target_nodes_never_cut", never_cut},
                          {"top_nodes", top.size()},
                          {"top_error_bound_mm", model.top_error_bound},
                          {"top_history_bound_mm", model.top_history_bound},
                          {"shape_nodes", model.shape_nodes.cols()},
                          {"model_mb", model_mb},
                          {"database_mb", db_mb},
                          {"size_ratio", model_mb / db_mb},
                          {"time_s", elapsed()},
                          {"machine", machine_info()},
                          {"files", {model_path.filename().string(), "target_modes.vtu", "final_shape_modes.vtu", "singular_values.csv", "singular_values.png", "summary.json"}}});
  if (!options.quiet) {
    std::printf("drom reduce: %s -> %s\n", db_path.string().c_str(), model_path.string().c_str());
    std::printf("  rank r            %d of %ld profiles (profile scale %.0f MPa)\n", model.rank(), static_cast<long>(db.B1.cols()), settings.profile_scale);
    std::printf("  error bound       %.3g mm (POD %.3g + histories %.3g; tolerance %.3g + %.3g)\n", model.error_bound(), model.pod_max_bound,
                model.history_bound, settings.tolerance, settings.history_tolerance);
    std::printf("  measured max err  %.3g mm against the database\n", report.measured_max_error);
    if (model.has_top()) std::printf("  stock's top       %zu nodes, measured max err %.3g mm where still there\n", top.size(), model.top_error_bound);
    std::printf("  size              %.2f MB (database %.1f MB)\n", model_mb, db_mb);
  }
  return 0;
}

}  // namespace drom::app
