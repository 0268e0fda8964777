#include "reduce/pod.hpp"

#include <Eigen/QR>
#include <Eigen/SVD>

#include <cmath>
#include <stdexcept>

namespace drom::reduce {

double max_norm_bound(const Eigen::VectorXd& singular_values, int r) { return singular_values.tail(singular_values.size() - r).sum(); }

double euclidean_bound(const Eigen::VectorXd& singular_values, int r) { return singular_values.tail(singular_values.size() - r).norm(); }

Pod truncated_pod(const Eigen::MatrixXd& snapshots, double tolerance, PodNorm norm, int max_rank) {
  if (!(tolerance >= 0) || !std::isfinite(tolerance)) throw std::invalid_argument("POD tolerance must be a finite number >= 0");
  if (!snapshots.allFinite()) throw std::invalid_argument("POD snapshots contain NaN or infinite values");
  const Eigen::Index n = snapshots.rows(), m = snapshots.cols();
  Pod pod;
  if (m == 0 || n == 0) {
    pod.modes.resize(n, 0);
    pod.right.resize(m, 0);
    return pod;
  }
  // A = Q R (Q: n x k, k = min(n, m)); R = Ur S V^T, so U = Q Ur.
  const Eigen::Index k = std::min(n, m);
  Eigen::HouseholderQR<Eigen::MatrixXd> qr(snapshots);
  const Eigen::MatrixXd R = qr.matrixQR().topRows(k).triangularView<Eigen::Upper>();
  Eigen::BDCSVD<Eigen::MatrixXd> svd(R, Eigen::ComputeThinU | Eigen::ComputeThinV);  // divide and conquer: R can be hundreds wide
  pod.singular_values = svd.singularValues();
  const auto bound = [&](int r) {
    return norm == PodNorm::Max ? max_norm_bound(pod.singular_values, r) : euclidean_bound(pod.singular_values, r);
  };
  int r = 0;
  const int cap = max_rank < 0 ? static_cast<int>(k) : std::min<int>(max_rank, static_cast<int>(k));
  while (r < cap && bound(r) > tolerance && pod.singular_values[r] > 0) ++r;  // a zero singular value carries nothing
  const Eigen::MatrixXd Q = qr.householderQ() * Eigen::MatrixXd::Identity(n, k);
  pod.modes = Q * svd.matrixU().leftCols(r);
  pod.right = svd.matrixV().leftCols(r);
  pod.max_bound = max_norm_bound(pod.singular_values, r);
  pod.euclidean_bound = euclidean_bound(pod.singular_values, r);
  return pod;
}

}  // namespace drom::reduce
