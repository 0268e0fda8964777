#include "reduce/light_model.hpp"

#include "support/file_format.hpp"
#include "support/hdf5_eigen.hpp"
#include "support/hdf5_reader.hpp"
#include "support/hdf5_writer.hpp"
#include "support/input_error.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
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

// Every number of a light model is a length (mm), a stress (MPa), a time (s), a mode amplitude or a
// factor of one, far inside 1e12 in a real model. Finite values near 1e306 passed, and the predictor's
// products overflowed: an infinite bound on the commanded offset (finding 26, docs/robustness.md).
constexpr double kLargestModelValue = 1e12;

Eigen::MatrixXd get(const Hdf5Reader& h5, const std::string& name) {
  Eigen::MatrixXd m = read_finite_matrix(h5, name);
  require_magnitude_within(h5, name, m, kLargestModelValue, "any length, stress, time or mode amplitude of a light model (|value| <= 1e12)");
  return m;
}

// Points stored one per row (x, y, z), as a 3 x n matrix. The shape is checked first: Eigen does not
// check a fixed-size assignment in release builds, and 4 columns overran the 3-row buffer (a
// heap-buffer-overflow the model_fields fuzzer found, finding 16 in docs/robustness.md).
Eigen::Matrix3Xd get_points(const Hdf5Reader& h5, const std::string& name) {
  const Eigen::MatrixXd m = get(h5, name);
  if (m.cols() != 3)
    throw InputError(h5.path().string() + ": dataset '" + name + "' has " + std::to_string(m.cols()) + " columns, expected 3 (x, y, z per row)");
  if (m.size() > 0 && m.cwiseAbs().maxCoeff() > 1e6) throw InputError(h5.path().string() + ": dataset '" + name + "': positions within 1e6 mm expected");
  return m.transpose();
}

// Indices and counts are stored as numbers: each must be whole and within [min, max] before it is an int.
int whole(const Hdf5Reader& h5, const std::string& name, double v, int min, int max) {
  if (!(v >= min && v <= max && v == std::floor(v)))
    throw InputError(h5.path().string() + ": " + name + " is " + std::to_string(v) + ", expected a whole number in [" + std::to_string(min) + ", " +
                     std::to_string(max) + "]");
  return static_cast<int>(v);
}

int count(const Hdf5Reader& h5, const std::string& attribute, int min, int max) { return whole(h5, attribute, h5.number_attribute(attribute), min, max); }

// A length or a bound: finite, and > 0 (or >= 0 when `zero_too`).
double measure(const Hdf5Reader& h5, const std::string& attribute, bool zero_too = true) {
  const double v = h5.number_attribute(attribute);
  if (!std::isfinite(v) || v < 0 || (!zero_too && v == 0))
    throw InputError(h5.path().string() + ": " + attribute + " is " + std::to_string(v) + ", expected a finite number " + (zero_too ? ">= 0" : "> 0"));
  return v;
}

std::vector<int> indices(const Hdf5Reader& h5, const std::string& name) {
  const Hdf5Matrix a = h5.matrix(name);
  std::vector<int> out;
  out.reserve(a.data.size());
  for (double v : a.data) out.push_back(whole(h5, "an index in " + name, v, 0, std::numeric_limits<int>::max()));
  return out;
}

// A surface the model carries over time (the target, the stock's top): `<name>_nodes`, `<name>_faces`
// (attribute `<name>_face_nodes`), `<name>_cut_time` (-1: never cut; HDF5 readers choke less on -1
// than on inf), and its mode histories `<histories>_<k>_space` / `_time` over `history_times`.
void put_surface(Hdf5Writer& h5, const std::string& name, const SurfaceMesh& mesh, const Eigen::VectorXd& cut_time, const std::string& histories,
                 const std::vector<SpaceTimeField>& modes) {
  h5.attribute(name + "_face_nodes", static_cast<double>(mesh.nodes_per_face()));
  put(h5, name + "_nodes", mesh.nodes().transpose());
  h5.write(name + "_faces", as_doubles(mesh.faces()), mesh.faces().size() / static_cast<std::size_t>(std::max(1, mesh.nodes_per_face())),
           static_cast<std::size_t>(mesh.nodes_per_face()));
  put(h5, name + "_cut_time", cut_time.unaryExpr([](double t) { return std::isfinite(t) ? t : -1.0; }).eval());
  for (std::size_t k = 0; k < modes.size(); ++k) {
    put_single(h5, histories + "_" + std::to_string(k) + "_space", modes[k].space());
    put_single(h5, histories + "_" + std::to_string(k) + "_time", modes[k].time());
  }
}

// The same read back and checked; errors name the file through `fail`.
template <class Fail>
void get_surface(const Hdf5Reader& h5, const std::string& name, const std::string& histories, int rank, const Eigen::VectorXd& times, const Fail& fail,
                 SurfaceMesh& mesh, Eigen::VectorXd& cut_time, std::vector<SpaceTimeField>& modes) {
  try {
    mesh = SurfaceMesh(get_points(h5, name + "_nodes"), indices(h5, name + "_faces"), count(h5, name + "_face_nodes", 1, 27));
  } catch (const std::invalid_argument& e) {
    throw fail(name + " surface: " + e.what());
  }
  cut_time = get(h5, name + "_cut_time").unaryExpr([](double t) { return t < 0 ? std::numeric_limits<double>::infinity() : t; });
  if (cut_time.size() != mesh.node_count()) throw fail(name + "_cut_time: one value per " + name + " node expected");
  for (int k = 0; k < rank; ++k) {
    const std::string field = histories + "_" + std::to_string(k);
    Eigen::MatrixXd space = get(h5, field + "_space"), time = get(h5, field + "_time");
    if (space.rows() != mesh.node_count()) throw fail(field + "_space: one row per " + name + " node expected");
    if (!space.allFinite() || !time.allFinite()) throw fail(field + " holds NaN or infinite values");
    try {
      modes.emplace_back(std::move(space), std::move(time), times, 0.0);
    } catch (const std::invalid_argument& e) {
      throw fail(field + ": " + e.what());
    }
  }
}

}  // namespace

void LightModel::write(const std::filesystem::path& file) const {
  Hdf5Writer h5(file);
  write_file_format(h5, kLightModel);
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
  h5.attribute("shape_face_nodes", static_cast<double>(shape_face_nodes));
  put_surface(h5, "target", target, target_cut_time, "history", histories);
  put(h5, "singular_values", singular_values);
  put(h5, "right", right);
  put(h5, "prior_sd", prior_sd);
  if (prior_covariance.size() > 0) put(h5, "prior_covariance", prior_covariance);
  if (prior_mean.size() > 0) put(h5, "prior_mean", prior_mean);
  if (!histories.empty()) put(h5, "history_times", histories.front().times());
  if (has_top()) {
    h5.attribute("top_history_bound_mm", top_history_bound);
    h5.attribute("top_error_bound_mm", top_error_bound);
    put_surface(h5, "top", top, top_cut_time, "top_history", top_histories);
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
  check_file_format(h5, kLightModel);
  LightModel m;
  m.case_toml = h5.text_attribute("case");
  m.database_hash = h5.text_attribute("database_hash");
  const int r = count(h5, "rank", 0, 100000);
  m.profile_scale = measure(h5, "profile_scale_mpa", false);
  m.tolerance = measure(h5, "tolerance_mm");
  m.history_tolerance = measure(h5, "history_tolerance_mm");
  m.pod_max_bound = measure(h5, "pod_max_bound_mm");
  m.pod_euclidean_bound = measure(h5, "pod_euclidean_bound_mm");
  m.history_bound = measure(h5, "history_bound_mm");
  m.tool_shape = h5.text_attribute("tool_shape") == "ball" ? ToolShape::Ball : ToolShape::Flat;
  m.tool_radius = measure(h5, "tool_radius_mm", false);
  m.pocket_depth = measure(h5, "pocket_depth_mm", false);
  m.shape_face_nodes = count(h5, "shape_face_nodes", 1, 27);
  m.singular_values = get(h5, "singular_values");
  m.right = get(h5, "right");
  m.prior_sd = get(h5, "prior_sd");
  if (h5.has("prior_covariance")) {
    m.prior_covariance = get(h5, "prior_covariance");
    if (m.prior_covariance.rows() != r || m.prior_covariance.cols() != r || !m.prior_covariance.allFinite())
      throw fail("prior_covariance: a finite rank x rank matrix expected");
    // A covariance: symmetric and positive definite, or the predictor cannot invert it (finding 20).
    const double scale = std::max(1e-300, m.prior_covariance.cwiseAbs().maxCoeff());
    if (r > 0 && ((m.prior_covariance - m.prior_covariance.transpose()).cwiseAbs().maxCoeff() > 1e-9 * scale ||
                  Eigen::LLT<Eigen::MatrixXd>(m.prior_covariance).info() != Eigen::Success))
      throw fail("prior_covariance: a symmetric positive definite matrix expected");
  }
  if (h5.has("prior_mean")) {
    m.prior_mean = get(h5, "prior_mean");
    if (m.prior_mean.size() != r || !m.prior_mean.allFinite()) throw fail("prior_mean: rank finite values expected");
  }
  if (m.right.cols() != r || m.prior_sd.size() != r || m.singular_values.size() < r) throw fail("rank " + std::to_string(r) + " disagrees with right / prior_sd / singular_values");
  const Eigen::VectorXd times = r > 0 ? Eigen::VectorXd(get(h5, "history_times")) : Eigen::VectorXd();
  get_surface(h5, "target", "history", r, times, fail, m.target, m.target_cut_time, m.histories);
  if (h5.has("top_nodes")) {
    m.top_history_bound = measure(h5, "top_history_bound_mm");
    m.top_error_bound = measure(h5, "top_error_bound_mm");
    get_surface(h5, "top", "top_history", r, times, fail, m.top, m.top_cut_time, m.top_histories);
  }
  m.shape_nodes = get_points(h5, "shape_nodes");
  m.shape_faces = indices(h5, "shape_faces");
  m.final_basis = get(h5, "final_basis");
  if (m.final_basis.rows() != 3 * m.shape_nodes.cols() || m.final_basis.cols() != r) throw fail("final_basis: (3 x shape nodes) x rank expected");
  m.path = get(h5, "path");
  if (m.path.cols() != 4) throw fail("path: 4 columns (x, y, z, program time) expected");
  // A machine's travel and a program's length: 1e6 mm and 1e7 s bound any real one, and keep the
  // cut-time index's arithmetic finite (finding 19).
  if (m.path.size() > 0 && (m.path.leftCols(3).cwiseAbs().maxCoeff() > 1e6 || m.path.col(3).cwiseAbs().maxCoeff() > 1e7))
    throw fail("path: positions within 1e6 mm and program times within 1e7 s expected");
  if (m.tool_radius > 1e3) throw fail("tool_radius_mm: a tool radius up to 1000 mm expected");
  if (!m.final_basis.allFinite() || !m.prior_sd.allFinite()) throw fail("final_basis or prior_sd holds NaN or infinite values");
  // A prior standard deviation near 1e-300 squares to zero and its precision is infinite: the same
  // overflow from below. Down to 1e-30 (precision 1e60) the predictor's arithmetic stays finite.
  if (r > 0 && !(m.prior_sd.array() >= 1e-30).all()) throw fail("prior_sd: standard deviations of at least 1e-30 expected");
  if (m.prior_covariance.size() > 0 && !(m.prior_covariance.diagonal().array() >= 1e-60).all())
    throw fail("prior_covariance: variances of at least 1e-60 expected on its diagonal");
  return m;
}

}  // namespace drom::reduce
