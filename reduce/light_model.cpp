#include "reduce/light_model.hpp"

#include "support/hdf5_reader.hpp"
#include "support/hdf5_writer.hpp"
#include "support/input_error.hpp"

#include <cmath>
#include <limits>

namespace drom::reduce {

namespace {

using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

std::vector<double> rows(const Eigen::MatrixXd& m) {
  std::vector<double> v(static_cast<std::size_t>(m.size()));
  Eigen::Map<RowMajor>(v.data(), m.rows(), m.cols()) = m;
  return v;
}

void put(Hdf5Writer& h5, const std::string& name, const Eigen::MatrixXd& m) {
  h5.write(name, rows(m), static_cast<std::size_t>(m.rows()), static_cast<std::size_t>(m.cols()));
}

// The bulky factors, already rounded to single precision by the reduction (its bound covers that).
void put_single(Hdf5Writer& h5, const std::string& name, const Eigen::MatrixXd& m) {
  const auto d = rows(m);
  h5.write(name, std::vector<float>(d.begin(), d.end()), static_cast<std::size_t>(m.rows()), static_cast<std::size_t>(m.cols()));
}

std::vector<double> as_doubles(const std::vector<int>& v) { return {v.begin(), v.end()}; }

Eigen::MatrixXd get(const Hdf5Reader& h5, const std::string& name) {
  const Hdf5Matrix m = h5.matrix(name);
  return Eigen::Map<const RowMajor>(m.data.data(), static_cast<Eigen::Index>(m.rows), static_cast<Eigen::Index>(m.cols));
}

}  // namespace

void LightModel::write(const std::filesystem::path& file) const {
  Hdf5Writer h5(file);
  h5.attribute("format", std::string("drom light model 1"));
  h5.attribute("layout", std::string(
                             "w(target node n, program time t) = sum_k alpha_k U1_k(n, t), U1_k = history_<k>_space (nodes x terms) "
                             "times the rows of history_<k>_time interpolated linearly in history_times; final shape (shape node i, "
                             "component c) = sum_k alpha_k final_basis[3 i + c, k]; alpha = diag(singular_values[:r]) right^T c / "
                             "profile_scale for profile coefficients c (MPa); prior alpha ~ N(prior_mean or 0, prior_covariance or diag(prior_sd^2))"));
  h5.attribute("case", case_toml);
  h5.attribute("database_hash", database_hash);
  h5.attribute("rank", static_cast<double>(rank()));
  h5.attribute("profile_scale_mpa", profile_scale);
  h5.attribute("tolerance_mm", tolerance);
  h5.attribute("history_tolerance_mm", history_tolerance);
  h5.attribute("pod_max_bound_mm", pod_max_bound);
  h5.attribute("pod_euclidean_bound_mm", pod_euclidean_bound);
  h5.attribute("history_bound_mm", history_bound);
  h5.attribute("tool_shape", std::string(tool_shape == ToolShape::Ball ? "ball" : "flat"));
  h5.attribute("tool_radius_mm", tool_radius);
  h5.attribute("pocket_depth_mm", pocket_depth);
  h5.attribute("target_face_nodes", static_cast<double>(target.nodes_per_face()));
  h5.attribute("shape_face_nodes", static_cast<double>(shape_face_nodes));
  put(h5, "target_nodes", target.nodes().transpose());
  h5.write("target_faces", as_doubles(target.faces()), target.faces().size() / static_cast<std::size_t>(std::max(1, target.nodes_per_face())),
           static_cast<std::size_t>(target.nodes_per_face()));
  Eigen::VectorXd cut = target_cut_time;
  for (auto& t : cut)
    if (!std::isfinite(t)) t = -1;  // HDF5 readers choke less on -1 than on inf: never cut
  put(h5, "target_cut_time", cut);
  put(h5, "singular_values", singular_values);
  put(h5, "right", right);
  put(h5, "prior_sd", prior_sd);
  if (prior_covariance.size() > 0) put(h5, "prior_covariance", prior_covariance);
  if (prior_mean.size() > 0) put(h5, "prior_mean", prior_mean);
  if (!histories.empty()) put(h5, "history_times", histories.front().times());
  for (int k = 0; k < rank(); ++k) {
    put_single(h5, "history_" + std::to_string(k) + "_space", histories[static_cast<std::size_t>(k)].space());
    put_single(h5, "history_" + std::to_string(k) + "_time", histories[static_cast<std::size_t>(k)].time());
  }
  if (has_top()) {
    h5.attribute("top_face_nodes", static_cast<double>(top.nodes_per_face()));
    h5.attribute("top_history_bound_mm", top_history_bound);
    h5.attribute("top_error_bound_mm", top_error_bound);
    put(h5, "top_nodes", top.nodes().transpose());
    h5.write("top_faces", as_doubles(top.faces()), top.faces().size() / static_cast<std::size_t>(std::max(1, top.nodes_per_face())),
             static_cast<std::size_t>(top.nodes_per_face()));
    Eigen::VectorXd top_cut = top_cut_time;
    for (auto& t : top_cut)
      if (!std::isfinite(t)) t = -1;
    put(h5, "top_cut_time", top_cut);
    for (int k = 0; k < rank(); ++k) {
      put_single(h5, "top_history_" + std::to_string(k) + "_space", top_histories[static_cast<std::size_t>(k)].space());
      put_single(h5, "top_history_" + std::to_string(k) + "_time", top_histories[static_cast<std::size_t>(k)].time());
    }
  }
  put(h5, "shape_nodes", shape_nodes.transpose());
  h5.write("shape_faces", as_doubles(shape_faces), shape_faces.size() / static_cast<std::size_t>(std::max(1, shape_face_nodes)),
           static_cast<std::size_t>(shape_face_nodes));
  put_single(h5, "final_basis", final_basis);
  put(h5, "path", path);
  h5.commit();
}

LightModel LightModel::read(const std::filesystem::path& file) {
  const Hdf5Reader h5(file);
  auto fail = [&](const std::string& what) { return InputError(file.string() + ": " + what); };
  if (h5.text_attribute("format") != "drom light model 1") throw fail("not a drom light model (attribute format)");
  LightModel m;
  m.case_toml = h5.text_attribute("case");
  m.database_hash = h5.text_attribute("database_hash");
  const int r = static_cast<int>(h5.number_attribute("rank"));
  m.profile_scale = h5.number_attribute("profile_scale_mpa");
  m.tolerance = h5.number_attribute("tolerance_mm");
  m.history_tolerance = h5.number_attribute("history_tolerance_mm");
  m.pod_max_bound = h5.number_attribute("pod_max_bound_mm");
  m.pod_euclidean_bound = h5.number_attribute("pod_euclidean_bound_mm");
  m.history_bound = h5.number_attribute("history_bound_mm");
  m.tool_shape = h5.text_attribute("tool_shape") == "ball" ? ToolShape::Ball : ToolShape::Flat;
  m.tool_radius = h5.number_attribute("tool_radius_mm");
  m.pocket_depth = h5.number_attribute("pocket_depth_mm");
  const int target_face_nodes = static_cast<int>(h5.number_attribute("target_face_nodes"));
  m.shape_face_nodes = static_cast<int>(h5.number_attribute("shape_face_nodes"));
  auto indices = [&](const std::string& name) {
    const Hdf5Matrix a = h5.matrix(name);
    std::vector<int> v;
    for (double x : a.data) v.push_back(static_cast<int>(x));
    return v;
  };
  try {
    m.target = SurfaceMesh(get(h5, "target_nodes").transpose(), indices("target_faces"), target_face_nodes);
  } catch (const std::invalid_argument& e) {
    throw fail(std::string("target surface: ") + e.what());
  }
  m.target_cut_time = get(h5, "target_cut_time");
  for (auto& t : m.target_cut_time)
    if (t < 0) t = std::numeric_limits<double>::infinity();
  if (m.target_cut_time.size() != m.target.node_count()) throw fail("target_cut_time: one value per target node expected");
  m.singular_values = get(h5, "singular_values");
  m.right = get(h5, "right");
  m.prior_sd = get(h5, "prior_sd");
  if (h5.has("prior_covariance")) {
    m.prior_covariance = get(h5, "prior_covariance");
    if (m.prior_covariance.rows() != r || m.prior_covariance.cols() != r || !m.prior_covariance.allFinite())
      throw fail("prior_covariance: a finite rank x rank matrix expected");
  }
  if (h5.has("prior_mean")) {
    m.prior_mean = get(h5, "prior_mean");
    if (m.prior_mean.size() != r || !m.prior_mean.allFinite()) throw fail("prior_mean: rank finite values expected");
  }
  if (m.right.cols() != r || m.prior_sd.size() != r || m.singular_values.size() < r) throw fail("rank " + std::to_string(r) + " disagrees with right / prior_sd / singular_values");
  const Eigen::VectorXd times = r > 0 ? Eigen::VectorXd(get(h5, "history_times")) : Eigen::VectorXd();
  for (int k = 0; k < r; ++k) {
    const std::string name = "history_" + std::to_string(k);
    Eigen::MatrixXd space = get(h5, name + "_space"), time = get(h5, name + "_time");
    if (space.rows() != m.target.node_count()) throw fail(name + "_space: one row per target node expected");
    try {
      m.histories.emplace_back(std::move(space), std::move(time), times, 0.0);
    } catch (const std::invalid_argument& e) {
      throw fail(name + ": " + e.what());
    }
  }
  if (h5.has("top_nodes")) {
    try {
      m.top = SurfaceMesh(get(h5, "top_nodes").transpose(), indices("top_faces"), static_cast<int>(h5.number_attribute("top_face_nodes")));
    } catch (const std::invalid_argument& e) {
      throw fail(std::string("top surface: ") + e.what());
    }
    m.top_history_bound = h5.number_attribute("top_history_bound_mm");
    m.top_error_bound = h5.number_attribute("top_error_bound_mm");
    m.top_cut_time = get(h5, "top_cut_time");
    for (auto& t : m.top_cut_time)
      if (t < 0) t = std::numeric_limits<double>::infinity();
    if (m.top_cut_time.size() != m.top.node_count()) throw fail("top_cut_time: one value per top node expected");
    for (int k = 0; k < r; ++k) {
      const std::string name = "top_history_" + std::to_string(k);
      Eigen::MatrixXd space = get(h5, name + "_space"), time = get(h5, name + "_time");
      if (space.rows() != m.top.node_count()) throw fail(name + "_space: one row per top node expected");
      if (!space.allFinite() || !time.allFinite()) throw fail(name + " holds NaN or infinite values");
      try {
        m.top_histories.emplace_back(std::move(space), std::move(time), times, 0.0);
      } catch (const std::invalid_argument& e) {
        throw fail(name + ": " + e.what());
      }
    }
  }
  m.shape_nodes = get(h5, "shape_nodes").transpose();
  m.shape_faces = indices("shape_faces");
  m.final_basis = get(h5, "final_basis");
  if (m.final_basis.rows() != 3 * m.shape_nodes.cols() || m.final_basis.cols() != r) throw fail("final_basis: (3 x shape nodes) x rank expected");
  m.path = get(h5, "path");
  if (m.path.cols() != 4) throw fail("path: 4 columns (x, y, z, program time) expected");
  for (int k = 0; k < r; ++k)
    if (!m.histories[static_cast<std::size_t>(k)].space().allFinite() || !m.histories[static_cast<std::size_t>(k)].time().allFinite())
      throw fail("history " + std::to_string(k) + " holds NaN or infinite values");
  if (!m.final_basis.allFinite() || !m.prior_sd.allFinite()) throw fail("final_basis or prior_sd holds NaN or infinite values");
  return m;
}

}  // namespace drom::reduce
