#include "reduce/model_reduction.hpp"

#include <chrono>
#include <stdexcept>

namespace drom::reduce {

namespace {

// sigma_k U_k as a space-time field within `tolerance` (mm), its factors rounded to single precision
// as the model file keeps them (the error, measured at the stations after rounding, covers what is
// written), stored per unit U_k.
SpaceTimeField compressed_history(const Eigen::MatrixXd& scaled, double sigma, const Eigen::VectorXd& times, double tolerance, double start, int& terms) {
  const SpaceTimeField field(scaled, times, tolerance, start);
  const Eigen::MatrixXd space = field.space().cast<float>().cast<double>();
  const Eigen::MatrixXd time = (field.time() / sigma).cast<float>().cast<double>();
  const double error = field.terms() == 0 ? (scaled.size() > 0 ? scaled.cwiseAbs().maxCoeff() : 0.0)
                                           : (scaled - sigma * space * time.bottomRows(times.size()).transpose()).cwiseAbs().maxCoeff();  // (a start instant may lead)
  terms += field.terms();
  return SpaceTimeField(space, time, field.times(), error / sigma);
}

// The r mode histories stacked in `modes` (row station * nodes + node, one column per mode), each
// compressed with tolerance / r; `bound` gets their compression errors' sum (mm).
std::vector<SpaceTimeField> compressed_modes(const Eigen::MatrixXd& modes, Eigen::Index nodes, const Eigen::VectorXd& sigma, const Eigen::VectorXd& times,
                                             double tolerance, double start, int& terms, double& bound) {
  const auto r = static_cast<int>(modes.cols());
  std::vector<SpaceTimeField> fields;
  bound = 0;
  for (int k = 0; k < r; ++k) {
    const Eigen::Map<const Eigen::MatrixXd> history(modes.col(k).data(), nodes, times.size());
    fields.push_back(compressed_history(sigma[k] * history, sigma[k], times, tolerance / r, start, terms));
    bound += sigma[k] * fields.back().bound();
  }
  return fields;
}

// Max over stations and nodes of |sum_k alpha_k U_k - database| (mm), where counts(node, station).
template <class Counts>
double measured_max_error(const std::vector<SpaceTimeField>& histories, const Eigen::VectorXd& times, const Eigen::MatrixXd& alpha, const Eigen::MatrixXd& scaled,
                          Eigen::Index nodes, Counts&& counts) {
  double error = 0;
  for (Eigen::Index s = 0; s < times.size(); ++s) {
    Eigen::MatrixXd at(nodes, static_cast<Eigen::Index>(histories.size()));
    for (std::size_t k = 0; k < histories.size(); ++k) at.col(static_cast<Eigen::Index>(k)) = histories[k].at(times[s]);
    const Eigen::MatrixXd e = at * alpha - scaled.middleRows(s * nodes, nodes);
    for (Eigen::Index n = 0; n < nodes; ++n)
      if (counts(n, s)) error = std::max(error, e.row(n).cwiseAbs().maxCoeff());
  }
  return error;
}

}  // namespace

void hold_after_cut(Eigen::Ref<Eigen::MatrixXd> history, const Eigen::VectorXd& station_times, const Eigen::VectorXd& cut_time) {
  for (Eigen::Index n = 0; n < history.rows(); ++n)
    for (Eigen::Index s = 1; s < history.cols(); ++s)
      if (station_times[s] > cut_time[n]) history(n, s) = history(n, s - 1);
}

ReductionReport reduce_snapshots(const SnapshotDatabase& db, const ReductionSettings& settings, LightModel& model) {
  const auto start = std::chrono::steady_clock::now();
  const Eigen::Index stations = db.station_times.size(), P = db.B1.cols();
  if (stations == 0 || db.B1.rows() % stations != 0) throw std::invalid_argument("B1 rows are not stations x target nodes");
  if (db.final_shape.cols() != P) throw std::invalid_argument("B1 and the final shape disagree on the number of profiles");
  if (!(settings.profile_scale > 0) || !(settings.tolerance >= 0) || !(settings.history_tolerance >= 0)) throw std::invalid_argument("reduction settings must be positive");
  const Eigen::Index nodes = db.B1.rows() / stations;

  // 1-2. POD of the scaled snapshots.
  const Eigen::MatrixXd A = settings.profile_scale * db.B1;
  const Pod pod = truncated_pod(A, settings.tolerance, PodNorm::Max, settings.max_rank);
  const int r = pod.rank();
  // All-zero snapshots (a database scaled by 0) keep no mode: a model that predicts nothing is no
  // model, and the empty blocks below would be arithmetic on a null pointer (finding 21).
  if (r == 0) throw std::invalid_argument("the snapshots hold no displacement above the tolerance: no mode to keep");
  model.singular_values = pod.singular_values;
  model.right = pod.right;
  model.profile_scale = settings.profile_scale;
  model.tolerance = settings.tolerance;
  model.history_tolerance = settings.history_tolerance;
  model.pod_max_bound = pod.max_bound;
  model.pod_euclidean_bound = pod.euclidean_bound;
  model.prior_sd = pod.singular_values.head(r);
  model.prior_covariance.resize(0, 0);
  if (settings.profile_sd.size() > 0) {
    if (settings.profile_sd.size() != P || !(settings.profile_sd.array() > 0).all())
      throw std::invalid_argument("profile_sd: one positive value per database column expected");
    const Eigen::MatrixXd L = pod.singular_values.head(r).asDiagonal() * pod.right.leftCols(r).transpose() * (settings.profile_sd / settings.profile_scale).asDiagonal();
    model.prior_covariance = L * L.transpose();
    model.prior_sd = model.prior_covariance.diagonal().cwiseSqrt();
  }

  model.prior_mean.resize(0);
  if (settings.profile_mean.size() > 0) {
    if (settings.profile_mean.size() != P || !settings.profile_mean.allFinite()) throw std::invalid_argument("profile_mean: one finite value per database column expected");
    model.prior_mean = pod.singular_values.head(r).asDiagonal() * pod.right.leftCols(r).transpose() * (settings.profile_mean / settings.profile_scale);
  }

  // 3. Space-time form of each history, compressed in mm (sigma_k U1_k), stored per unit U1_k.
  ReductionReport report;
  model.histories = compressed_modes(pod.modes.leftCols(r), nodes, pod.singular_values, db.station_times, settings.history_tolerance, db.program_start,
                                     report.history_terms, model.history_bound);

  // 4. The stock's top: the same combination of its snapshots, held after each node's cut.
  model.top_histories.clear();
  model.top_history_bound = 0;
  const Eigen::Index top_nodes = db.B1_top.size() > 0 ? db.B1_top.rows() / stations : 0;
  Eigen::MatrixXd top_scaled;
  if (top_nodes > 0) {
    if (db.B1_top.rows() != top_nodes * stations || db.B1_top.cols() != P || db.top_cut_time.size() != top_nodes)
      throw std::invalid_argument("B1_top is not (stations x top nodes) x profiles with a cut time per top node");
    top_scaled = settings.profile_scale * db.B1_top;
    for (Eigen::Index p = 0; p < P; ++p) hold_after_cut(Eigen::Map<Eigen::MatrixXd>(top_scaled.col(p).data(), top_nodes, stations), db.station_times, db.top_cut_time);
    const Eigen::MatrixXd top_modes = top_scaled * pod.right.leftCols(r) * pod.singular_values.head(r).cwiseInverse().asDiagonal();  // U1_top, stacked
    model.top_histories = compressed_modes(top_modes, top_nodes, pod.singular_values, db.station_times, settings.history_tolerance, db.program_start,
                                           report.history_terms, model.top_history_bound);
  }

  // 5. Final-shape basis: alpha = D V^T c / s maps back to B2 c.
  model.final_basis = (settings.profile_scale * db.final_shape * pod.right * pod.singular_values.head(r).cwiseInverse().asDiagonal()).cast<float>().cast<double>();

  // What the model gives for each database column, against the column (both in mm at profile_scale).
  const Eigen::MatrixXd alpha = pod.singular_values.head(r).asDiagonal() * pod.right.transpose();  // r x P
  report.measured_max_error = measured_max_error(model.histories, db.station_times, alpha, A, nodes, [](Eigen::Index, Eigen::Index) { return true; });
  // And on the top, where the material is still there (the POD did not choose its modes for the top,
  // so this is the top's only bound: truncation and compression together).
  if (top_nodes > 0)
    report.top_measured_max_error = measured_max_error(model.top_histories, db.station_times, alpha, top_scaled, top_nodes,
                                                       [&](Eigen::Index n, Eigen::Index s) { return db.station_times[s] <= db.top_cut_time[n]; });
  model.top_error_bound = report.top_measured_max_error;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace drom::reduce
