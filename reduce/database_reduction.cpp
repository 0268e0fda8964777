#include "reduce/database_reduction.hpp"

#include "reduce/cut_time.hpp"
#include "support/atomic_file.hpp"
#include "support/file_format.hpp"
#include "support/hdf5_eigen.hpp"
#include "support/hdf5_reader.hpp"
#include "support/input_error.hpp"
#include "support/png_plot.hpp"
#include "support/summary.hpp"
#include "support/vtk_fields.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace drom::reduce {

namespace {

std::vector<int> as_indices(const Eigen::MatrixXd& m, Eigen::Index bound, const std::filesystem::path& file, const std::string& what) {
  std::vector<int> out(static_cast<std::size_t>(m.size()));
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c) {
      const double v = m(r, c);
      if (!(v >= 0 && v < static_cast<double>(bound) && v == std::floor(v))) throw InputError(file.string() + ": " + what + " holds an index out of range");
      out[static_cast<std::size_t>(r * m.cols() + c)] = static_cast<int>(v);
    }
  return out;
}

// A surface on these global nodes: coordinates from the mesh, faces as rows of local indices.
SurfaceMesh surface(const Eigen::MatrixXd& xyz, const std::vector<int>& nodes, const Eigen::MatrixXd& faces, const std::filesystem::path& file,
                    const std::string& what) {
  Eigen::Matrix3Xd points(3, static_cast<Eigen::Index>(nodes.size()));
  for (std::size_t i = 0; i < nodes.size(); ++i) points.col(static_cast<Eigen::Index>(i)) = xyz.row(nodes[i]).transpose();
  if (faces.rows() == 0) throw InputError(file.string() + ": no face on the " + what);
  try {
    return SurfaceMesh(points, as_indices(faces, static_cast<Eigen::Index>(nodes.size()), file, what + " faces"), static_cast<int>(faces.cols()));
  } catch (const std::invalid_argument& e) {
    throw InputError(file.string() + ": the " + what + ": " + e.what());  // finding 23: faces of 1 node
  }
}

// Displacements per unit profile (mm) and times (s) from a real job are far inside these bounds;
// finite values near 1e300 would overflow the POD's products into infinities (finding 17).
void bounded(const Hdf5Reader& h5, const Eigen::MatrixXd& m, const std::string& name, double most = 1e7,
             const std::string& what = "any displacement (mm) or time (s) of a job (|value| <= 1e7)") {
  require_magnitude_within(h5, name, m, most, what);
}

// What every reduction reads: the snapshots over the stations and their times, the final shape, the
// mesh's nodes, the pocket and the target's nodes, checked against each other.
struct DatabaseContents {
  SnapshotDatabase db;
  Eigen::MatrixXd B2, xyz, pocket;
  std::vector<int> target;
};

DatabaseContents read_snapshots(const Hdf5Reader& h5, const std::filesystem::path& db_path) {
  DatabaseContents in;
  SnapshotDatabase& db = in.db;
  db.B1 = read_finite_matrix(h5, "B1");
  bounded(h5, db.B1, "B1");
  const Eigen::MatrixXd station_time = read_finite_matrix(h5, "station_time");
  if (station_time.cols() != 1) throw InputError(db_path.string() + ": dataset 'station_time': one column (a time per station) expected");
  bounded(h5, station_time, "station_time");
  db.station_times = station_time.col(0);
  // Stations come in program order: two out of order (or at one instant) made the histories'
  // interpolation divide by a zero or negative step, an infinite error bound accepted (finding 18).
  for (Eigen::Index s = 1; s < db.station_times.size(); ++s)
    if (!(db.station_times(s) > db.station_times(s - 1)))
      throw InputError(db_path.string() + ": dataset 'station_time': station " + std::to_string(s) + " at " + std::to_string(db.station_times(s)) +
                       " s does not follow station " + std::to_string(s - 1) + " at " + std::to_string(db.station_times(s - 1)) + " s: increasing program times expected");
  in.B2 = read_finite_matrix(h5, "B2"), in.xyz = read_finite_matrix(h5, "node_coordinates");
  bounded(h5, in.B2, "B2"), bounded(h5, in.xyz, "node_coordinates");
  in.pocket = read_finite_matrix(h5, "pocket");
  if (in.xyz.cols() != 3) throw InputError(db_path.string() + ": node_coordinates: 3 columns expected");
  if (in.pocket.size() != 5) throw InputError(db_path.string() + ": pocket: x_min, y_min, length_x, length_y, depth expected");
  in.target = as_indices(read_finite_matrix(h5, "target_nodes"), in.xyz.rows(), db_path, "target_nodes");
  const auto nt = in.target.size();
  if (nt == 0 || db.B1.rows() != static_cast<Eigen::Index>(nt) * db.station_times.size())
    throw InputError(db_path.string() + ": B1 has " + std::to_string(db.B1.rows()) + " rows, expected stations x target nodes");
  if (in.B2.rows() != 3 * in.xyz.rows() || in.B2.cols() != db.B1.cols()) throw InputError(db_path.string() + ": B2 is not (3 x nodes) x profiles");
  if (!db.B1.allFinite() || !in.B2.allFinite()) throw InputError(db_path.string() + ": B1 or B2 holds NaN or infinite values");
  return in;
}

// 1. Surfaces: the target, and the final part's (its B2 rows are the final shape).
void read_surfaces(const Hdf5Reader& h5, const std::filesystem::path& db_path, DatabaseContents& in, LightModel& model) {
  model.target = surface(in.xyz, in.target, read_finite_matrix(h5, "target_faces"), db_path, "target surface");
  const std::vector<int> shape = as_indices(read_finite_matrix(h5, "shape_nodes"), in.xyz.rows(), db_path, "shape_nodes");
  const SurfaceMesh shape_surface = surface(in.xyz, shape, read_finite_matrix(h5, "shape_faces"), db_path, "final part");
  model.shape_nodes = shape_surface.nodes();
  model.shape_faces = shape_surface.faces();
  model.shape_face_nodes = shape_surface.nodes_per_face();
  in.db.final_shape.resize(3 * static_cast<Eigen::Index>(shape.size()), in.B2.cols());
  for (std::size_t i = 0; i < shape.size(); ++i)
    in.db.final_shape.middleRows(3 * static_cast<Eigen::Index>(i), 3) = in.B2.middleRows(3 * shape[i], 3);
}

// The top's faces: those of the stock's top face whose nodes all lie within the margin (`local`: a
// top node's index among those kept, -1 if it is not).
Eigen::MatrixXd faces_within_margin(const Hdf5Reader& h5, const std::filesystem::path& db_path, Eigen::Index ntop, const std::vector<int>& local) {
  const Eigen::MatrixXd top_faces = read_finite_matrix(h5, "top_faces");
  std::vector<Eigen::Index> keep_faces;
  const auto all_faces = as_indices(top_faces, ntop, db_path, "top_faces");
  for (Eigen::Index f = 0; f < top_faces.rows(); ++f) {
    bool inside = true;
    for (Eigen::Index k = 0; k < top_faces.cols(); ++k) inside = inside && local[static_cast<std::size_t>(all_faces[static_cast<std::size_t>(f * top_faces.cols() + k)])] >= 0;
    if (inside) keep_faces.push_back(f);
  }
  Eigen::MatrixXd faces(static_cast<Eigen::Index>(keep_faces.size()), top_faces.cols());
  for (std::size_t f = 0; f < keep_faces.size(); ++f)
    for (Eigen::Index k = 0; k < top_faces.cols(); ++k)
      faces(static_cast<Eigen::Index>(f), k) = local[static_cast<std::size_t>(all_faces[static_cast<std::size_t>(keep_faces[f] * top_faces.cols() + k)])];
  return faces;
}

// 2. The stock's top within `margin` of the pocket's footprint, in the part's own coordinates: its
// snapshots and its surface. Returns its nodes.
std::vector<int> read_top(const Hdf5Reader& h5, const std::filesystem::path& db_path, double margin, DatabaseContents& in, LightModel& model) {
  SnapshotDatabase& db = in.db;
  const double x0 = in.pocket(0), y0 = in.pocket(1), lx = in.pocket(2), ly = in.pocket(3);
  std::vector<int> top;
  if (!h5.has("B1_top")) throw InputError(db_path.string() + ": no B1_top; run drom offline again for --top-margin");
  const Eigen::MatrixXd B1_top = read_finite_matrix(h5, "B1_top"), uvt = read_finite_matrix(h5, "top_parametric");
  bounded(h5, B1_top, "B1_top"), bounded(h5, uvt, "top_parametric");
  const std::vector<int> top_ids = as_indices(read_finite_matrix(h5, "top_nodes"), in.xyz.rows(), db_path, "top_nodes");
  const auto ntop = static_cast<Eigen::Index>(top_ids.size());
  const Eigen::Index ns = db.station_times.size();
  if (ntop == 0 || B1_top.rows() != ntop * ns || B1_top.cols() != db.B1.cols())
    throw InputError(db_path.string() + ": B1_top has " + std::to_string(B1_top.rows()) + " rows, expected stations x top nodes");
  // Its columns too: a one-column top_parametric was read past its end (an ASan heap-buffer-overflow,
  // finding 28 in docs/robustness.md).
  if (uvt.rows() != ntop || uvt.cols() != 3)
    throw InputError(db_path.string() + ": top_parametric is " + std::to_string(uvt.rows()) + " x " + std::to_string(uvt.cols()) +
                     ", expected one row (u, v, t) per top node: " + std::to_string(ntop) + " x 3");
  if (!B1_top.allFinite()) throw InputError(db_path.string() + ": B1_top holds NaN or infinite values");
  std::vector<Eigen::Index> rows;
  const double m = margin + 1e-9;
  for (Eigen::Index i = 0; i < ntop; ++i) {
    if (uvt(i, 0) < x0 - m || uvt(i, 0) > x0 + lx + m || uvt(i, 1) < y0 - m || uvt(i, 1) > y0 + ly + m) continue;
    top.push_back(top_ids[static_cast<std::size_t>(i)]);
    rows.push_back(i);
  }
  const auto kept = static_cast<Eigen::Index>(top.size());
  db.B1_top.resize(kept * ns, B1_top.cols());
  for (Eigen::Index j = 0; j < kept; ++j)
    for (Eigen::Index s = 0; s < ns; ++s) db.B1_top.row(s * kept + j) = B1_top.row(s * ntop + rows[static_cast<std::size_t>(j)]);
  std::vector<int> local(static_cast<std::size_t>(ntop), -1);
  for (Eigen::Index j = 0; j < kept; ++j) local[static_cast<std::size_t>(rows[static_cast<std::size_t>(j)])] = static_cast<int>(j);
  model.top = surface(in.xyz, top, faces_within_margin(h5, db_path, ntop, local), db_path, "stock's top within --top-margin of the pocket");
  return top;
}

// 3. Path, tool, and when each target (and top) node was cut.
void compute_cut_times(const Hdf5Reader& h5, const std::filesystem::path& db_path, std::size_t top_nodes, DatabaseContents& in,
                       DatabaseReduction& out) {
  LightModel& model = out.model;
  SnapshotDatabase& db = in.db;
  const double depth = in.pocket(4);
  const Eigen::MatrixXd cutting = read_finite_matrix(h5, "path_cutting");
  model.path = read_finite_matrix(h5, "path_waypoints");
  bounded(h5, model.path, "path_waypoints");
  if (model.path.cols() != 4 || cutting.rows() != model.path.rows() || cutting.cols() != 1 || model.path.rows() < 2 || !model.path.allFinite())
    throw InputError(db_path.string() + ": path_waypoints / path_cutting: rows of x, y, z, t and one flag per row expected");
  std::vector<char> cut(static_cast<std::size_t>(cutting.rows()));
  for (Eigen::Index i = 0; i < cutting.rows(); ++i) cut[static_cast<std::size_t>(i)] = cutting(i, 0) != 0;
  const std::string tool_kind = h5.text_attribute("tool_kind");
  const double tool_radius = h5.number_attribute("tool_radius");
  model.tool_shape = tool_kind == "ball" ? ToolShape::Ball : ToolShape::Flat;
  model.tool_radius = tool_radius;
  model.pocket_depth = depth;
  const std::size_t nt = out.target_nodes;
  model.target_cut_time.resize(static_cast<Eigen::Index>(nt));
  const double z_tolerance = 0.02 * depth;
  const Eigen::Matrix3Xd& target_xyz = model.target.nodes();
  for (std::size_t i = 0; i < nt; ++i)
    model.target_cut_time[static_cast<Eigen::Index>(i)] = first_cover_time(model.path, cut, target_xyz.col(static_cast<Eigen::Index>(i)), tool_radius, z_tolerance);
  for (double t : model.target_cut_time) out.target_nodes_never_cut += !std::isfinite(t);
  // A top node is gone once the tool has been down to the floor under it.
  model.top_cut_time.resize(static_cast<Eigen::Index>(top_nodes));
  for (std::size_t i = 0; i < top_nodes; ++i)
    model.top_cut_time[static_cast<Eigen::Index>(i)] =
        first_cover_time(model.path, cut, model.top.nodes().col(static_cast<Eigen::Index>(i)) - Eigen::Vector3d(0, 0, depth), tool_radius, z_tolerance);
  db.top_cut_time = model.top_cut_time;
  db.program_start = 0;
}

// 4. The reduction's settings: the tolerances, and the prior from the case's own coefficients when
// they are the database's columns' profile.
ReductionSettings reduction_settings(const Hdf5Reader& h5, const DatabaseReductionSettings& options, Eigen::Index columns) {
  ReductionSettings settings;
  settings.tolerance = options.tolerance;
  settings.history_tolerance = options.history_tolerance >= 0 ? options.history_tolerance : 0.5 * options.tolerance;
  // The case's coefficients in the database's column order, when they are its columns' profile.
  const Eigen::VectorXd case_coefficients = h5.has("case_coefficients") ? Eigen::VectorXd(read_finite_matrix(h5, "case_coefficients").reshaped()) : Eigen::VectorXd();
  // The case's profile coefficients are stresses: -1.8e308 MPa made the prior's scale infinite and
  // the model's error bound with it (finding 18).
  bounded(h5, case_coefficients, "case_coefficients", 1e4, "any residual stress (MPa) (|value| <= 1e4)");
  const bool case_columns = case_coefficients.size() > 0 && case_coefficients.size() == columns;
  const double largest = case_coefficients.size() > 0 ? case_coefficients.cwiseAbs().maxCoeff() : 0.0;
  settings.profile_scale = options.profile_scale > 0 ? options.profile_scale : (largest > 0 ? largest : 50.0);
  settings.max_rank = options.max_rank;
  // The prior: each unit profile's coefficient at the case's own magnitude for that direction and
  // degree (a rolled plate's stresses fall with the degree), floored at a tenth of the largest.
  if (options.profile_scale <= 0 && case_columns) settings.profile_sd = case_coefficients.cwiseAbs().cwiseMax(0.1 * settings.profile_scale);
  // The prior's mean: the case's own profile, the one the stock is expected to carry (a quenched
  // plate's skins are in compression, not as likely in tension: a zero mean would say they are).
  if (options.prior_mean_from_case && case_columns) settings.profile_mean = case_coefficients;
  return settings;
}

// Target modes at the last station with the cut times, and the final part's modes (warp by vector in
// ParaView).
void write_mode_pictures(const std::filesystem::path& out_dir, const DatabaseReduction& r) {
  const LightModel& model = r.model;
  VtuFields target_fields, shape_fields;
  std::vector<double> cut(model.target_cut_time.data(), model.target_cut_time.data() + model.target_cut_time.size());
  for (double& t : cut)
    if (!std::isfinite(t)) t = -1;
  target_fields.point_scalars.emplace_back("cut_time_s", cut);
  const double t_end = r.last_station_time;
  for (int k = 0; k < model.rank(); ++k) {
    const Eigen::VectorXd u = model.histories[static_cast<std::size_t>(k)].at(t_end) * model.prior_sd[k];
    target_fields.point_scalars.emplace_back("U1_" + std::to_string(k + 1) + "_end_mm", std::vector<double>(u.data(), u.data() + u.size()));
    shape_fields.point_vectors.emplace_back("U2_" + std::to_string(k + 1) + "_mm", model.final_basis.col(k) * model.prior_sd[k]);
  }
  write_surface_vtu(out_dir / "target_modes.vtu", model.target.nodes(), model.target.faces(), model.target.nodes_per_face(), target_fields);
  write_surface_vtu(out_dir / "final_shape_modes.vtu", model.shape_nodes, model.shape_faces, model.shape_face_nodes, shape_fields);
}

// The singular values against the tolerance: where the POD stopped, and why.
void write_singular_values(const std::filesystem::path& out_dir, const DatabaseReduction& r) {
  const LightModel& model = r.model;
  std::string csv = "i,singular_value_mm,bound_if_truncated_here_mm,kept\n";
  PlotSeries values{"singular value", {}, {}, "o-"}, bounds{"bound if truncated after i", {}, {}, "s--"};
  for (Eigen::Index i = 0; i < model.singular_values.size(); ++i) {
    const double bound = max_norm_bound(model.singular_values, static_cast<int>(i + 1));
    char line[128];
    std::snprintf(line, sizeof line, "%ld,%.9e,%.9e,%d\n", static_cast<long>(i + 1), model.singular_values[i], bound, i < model.rank() ? 1 : 0);
    csv += line;
    values.x.push_back(static_cast<double>(i + 1)), values.y.push_back(model.singular_values[i]);
    bounds.x.push_back(static_cast<double>(i + 1)), bounds.y.push_back(bound > 0 ? bound : std::nan(""));
  }
  write_file_atomically(out_dir / "singular_values.csv", csv);
  PlotSpec plot;
  plot.title = "POD of B1 (" + r.case_name + "): r = " + std::to_string(model.rank());
  plot.x_label = "mode i";
  plot.y_label = "mm (plausible profile)";
  plot.series = {values, bounds};
  plot.hlines = {{"tolerance", r.settings.tolerance}};
  plot.log_y = true;
  write_png_plot(out_dir / "singular_values.png", plot);
}

nlohmann::json reduction_summary(const std::filesystem::path& model_path, const DatabaseReduction& r, double seconds) {
  const LightModel& model = r.model;
  const double model_mb = static_cast<double>(std::filesystem::file_size(model_path)) / 1048576.0;
  const double db_mb = static_cast<double>(std::filesystem::file_size(r.database)) / 1048576.0;
  std::vector<double> sigma(model.singular_values.data(), model.singular_values.data() + model.singular_values.size());
  return {{"command", "reduce"},
          {"case", r.case_name},
          {"database", r.database.string()},
          {"database_hash", model.database_hash},
          {"model", model_path.filename().string()},
          {"rank", model.rank()},
          {"prior", model.prior_covariance.size() > 0 ? "each unit profile at the case's own coefficient magnitude (full covariance)"
                                                      : "every unit profile at profile_scale (diagonal)"},
          {"prior_mean", model.prior_mean.size() > 0 ? "the case's [stress] profile" : "zero"},
          {"profiles", r.profiles},
          {"profile_scale_mpa", r.settings.profile_scale},
          {"tolerance_mm", r.settings.tolerance},
          {"history_tolerance_mm", r.settings.history_tolerance},
          {"pod_max_bound_mm", model.pod_max_bound},
          {"pod_euclidean_bound_mm", model.pod_euclidean_bound},
          {"history_bound_mm", model.history_bound},
          {"error_bound_mm", model.error_bound()},
          {"measured_max_error_mm", r.report.measured_max_error},
          {"history_terms", r.report.history_terms},
          {"singular_values_mm", sigma},
          {"target_nodes", r.target_nodes},
          {"target_nodes_never_cut", r.target_nodes_never_cut},
          {"top_nodes", r.top_nodes},
          {"top_error_bound_mm", model.top_error_bound},
          {"top_history_bound_mm", model.top_history_bound},
          {"shape_nodes", model.shape_nodes.cols()},
          {"model_mb", model_mb},
          {"database_mb", db_mb},
          {"size_ratio", model_mb / db_mb},
          {"time_s", seconds},
          {"machine", machine_info()},
          {"files", {model_path.filename().string(), "target_modes.vtu", "final_shape_modes.vtu", "singular_values.csv", "singular_values.png", "summary.json"}}};
}

}  // namespace

DatabaseReduction reduce_database(const std::filesystem::path& db_path, const DatabaseReductionSettings& options) {
  const Hdf5Reader h5(db_path);
  check_file_format(h5, kSnapshotDatabase);
  if (h5.text_attribute("kind") != "offline")
    throw InputError(db_path.string() + ": a '" + h5.text_attribute("kind") + "' database; reduce needs an offline one (one column per unit profile)");
  DatabaseReduction out;
  out.database = db_path;
  out.case_name = h5.text_attribute("case_name");
  DatabaseContents in = read_snapshots(h5, db_path);
  SnapshotDatabase& db = in.db;
  out.profiles = static_cast<long>(db.B1.cols());
  out.last_station_time = db.station_times.size() > 0 ? db.station_times[db.station_times.size() - 1] : 0.0;
  out.target_nodes = in.target.size();

  LightModel& model = out.model;
  read_surfaces(h5, db_path, in, model);
  const std::vector<int> top = options.top_margin >= 0 ? read_top(h5, db_path, options.top_margin, in, model) : std::vector<int>();
  out.top_nodes = top.size();
  compute_cut_times(h5, db_path, top.size(), in, out);

  out.settings = reduction_settings(h5, options, db.B1.cols());
  try {
    out.report = reduce_snapshots(db, out.settings, model);
  } catch (const std::invalid_argument& e) {
    // What the reduction refuses comes from the file's numbers: name the file (defence in depth
    // behind the bounds above).
    throw InputError(db_path.string() + ": its snapshots cannot be reduced: " + e.what());
  }
  model.case_toml = h5.text_attribute("case");
  model.database_hash = h5.text_attribute("content_hash");
  return out;
}

nlohmann::json write_reduction(const std::filesystem::path& model_path, const DatabaseReduction& r, double seconds) {
  const std::filesystem::path out_dir = model_path.has_parent_path() ? model_path.parent_path() : std::filesystem::path(".");
  clear_earlier_run(out_dir, "reduce");
  std::filesystem::create_directories(out_dir);
  r.model.write(model_path);
  write_mode_pictures(out_dir, r);
  write_singular_values(out_dir, r);
  const nlohmann::json summary = reduction_summary(model_path, r, seconds);
  write_summary(out_dir, summary);
  return summary;
}

}  // namespace drom::reduce
