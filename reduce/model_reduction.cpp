#include "reduce/model_reduction.hpp"

#include <chrono>
#include <stdexcept>

namespace drom::reduce {

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

  // 3. Space-time form of each history, compressed in mm (sigma_k U1_k), stored per unit U1_k.
  ReductionReport report;
  model.histories.clear();
  model.history_bound = 0;
  for (int k = 0; k < r; ++k) {
    const double sigma = pod.singular_values[k];
    const Eigen::Map<const Eigen::MatrixXd> history(pod.modes.col(k).data(), nodes, stations);
    const Eigen::MatrixXd target = sigma * history;
    const SpaceTimeField scaled(target, db.station_times, settings.history_tolerance / r, db.program_start);
    // The model file keeps the factors in single precision (half the size): round them here, and
    // measure the rounded form's error at the stations, so the bound covers what is written.
    const Eigen::MatrixXd space = scaled.space().cast<float>().cast<double>();
    const Eigen::MatrixXd time = (scaled.time() / sigma).cast<float>().cast<double>();
    const double error = (target - sigma * space * time.bottomRows(stations).transpose()).cwiseAbs().maxCoeff();  // (a start instant may lead)
    model.histories.emplace_back(space, time, scaled.times(), error / sigma);
    model.history_bound += error;
    report.history_terms += scaled.terms();
  }

  // 4. Final-shape basis: alpha = D V^T c / s maps back to B2 c.
  model.final_basis = (settings.profile_scale * db.final_shape * pod.right * pod.singular_values.head(r).cwiseInverse().asDiagonal()).cast<float>().cast<double>();

  // What the model gives for each database column, against the column (both in mm at profile_scale).
  const Eigen::MatrixXd alpha = pod.singular_values.head(r).asDiagonal() * pod.right.transpose();  // r x P
  for (Eigen::Index s = 0; s < stations; ++s) {
    Eigen::MatrixXd at(nodes, r);
    for (int k = 0; k < r; ++k) at.col(k) = model.histories[static_cast<std::size_t>(k)].at(db.station_times[s]);
    const Eigen::MatrixXd w = at * alpha;
    report.measured_max_error = std::max(report.measured_max_error, (w - A.middleRows(s * nodes, nodes)).cwiseAbs().maxCoeff());
  }
  report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return report;
}

}  // namespace drom::reduce
