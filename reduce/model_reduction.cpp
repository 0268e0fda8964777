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
  const double error = (scaled - sigma * space * time.bottomRows(times.size()).transpose()).cwiseAbs().maxCoeff();  // (a start instant may lead)
  terms += field.terms();
  return SpaceTimeField(space, time, field.times(), error / sigma);
}

}  // namespace

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
  model.histories.clear();
  model.history_bound = 0;
  for (int k = 0; k < r; ++k) {
    const double sigma = pod.singular_values[k];
    const Eigen::Map<const Eigen::MatrixXd> history(pod.modes.col(k).data(), nodes, stations);
    model.histories.push_back(compressed_history(sigma * history, sigma, db.station_times, settings.history_tolerance / r, db.program_start, report.history_terms));
    model.history_bound += sigma * model.histories.back().bound();
  }

  // 4. The stock's top: the same combination of its snapshots, held after each node's cut.
  model.top_histories.clear();
  model.top_history_bound = 0;
  const Eigen::Index top_nodes = db.B1_top.size() > 0 ? db.B1_top.rows() / stations : 0;
  Eigen::MatrixXd top_scaled;
  if (top_nodes > 0) {
    if (db.B1_top.rows() != top_nodes * stations || db.B1_top.cols() != P || db.top_cut_time.size() != top_nodes)
      throw std::invalid_argument("B1_top is not (stations x top nodes) x profiles with a cut time per top node");
    top_scaled = settings.profile_scale * db.B1_top;
    for (Eigen::Index n = 0; n < top_nodes; ++n)
      for (Eigen::Index s = 1; s < stations; ++s)
        if (db.station_times[s] > db.top_cut_time[n]) top_scaled.row(s * top_nodes + n) = top_scaled.row((s - 1) * top_nodes + n);
    const Eigen::MatrixXd top_modes = top_scaled * pod.right.leftCols(r) * pod.singular_values.head(r).cwiseInverse().asDiagonal();  // U1_top, stacked
    for (int k = 0; k < r; ++k) {
      const double sigma = pod.singular_values[k];
      const Eigen::Map<const Eigen::MatrixXd> history(top_modes.col(k).data(), top_nodes, stations);
      model.top_histories.push_back(compressed_history(sigma * history, sigma, db.station_times, settings.history_tolerance / r, db.program_start, report.history_terms));
      model.top_history_bound += sigma * model.top_histories.back().bound();
    }
  }

  // 5. Final-shape basis: alpha = D V^T c / s maps back to B2 c.
  model.final_basis = (settings.profile_scale * db.final_shape * pod.right * pod.singular_values.head(r).cwiseInverse().asDiagonal()).cast<float>().cast<double>();

  // What the model gives for each database column, against the column (both in mm at profile_scale).
  const Eigen::MatrixXd alpha = pod.singular_values.head(r).asDiagonal() * pod.right.transpose();  // r x P
  for (Eigen::Index s = 0; s < stations; ++s) {
    Eigen::MatrixXd at(nodes, r);
    for (int k = 0; k < r; ++k) at.col(k) = model.histories[static_cast<std::size_t>(k)].at(db.station_times[s]);
    const Eigen::MatrixXd w = at * alpha;
    report.measured_max_error = std::max(report.measured_max_error, (w - A.middleRows(s * nodes, nodes)).cwiseAbs().maxCoeff());
  }
  // And on the top, where the material is still there (the POD did not choose its modes for the top,
  // so this is the top's only bound: truncation and compression together).
  for (Eigen::Index s = 0; s < stations && top_nodes > 0; ++s) {
    Eigen::MatrixXd at(top_nodes, r);
    for (int k = 0; k < r; ++k) at.col(k) = model.top_histories[static_cast<std::size_t>(k)].at(db.station_times[s]);
    const Eigen::MatrixXd e = at * alpha - top_scaled.middleRows(s * top_nodes, top_nodes);
    for (Eigen::Index n = 0; n < top_nodes; ++n)
      if (db.station_times[s] <= db.top_cut_time[n]) report.top_measured_max_error = std::max(report.top_measured_max_error, e.row(n).cwiseAbs().maxCoeff());
  }
  model.top_error_bound = report.top_measured_max_error;
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace drom::reduce
