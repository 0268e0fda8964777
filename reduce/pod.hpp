#pragma once
// Snapshot POD truncated by the seed's error bounds (docs/design.md §5; seed eqs. 2.9 and 2.12).
// With A = U D V^T and r modes kept, the part of snapshot j the modes miss is
//   E_j = sum_{i>r} sigma_i V_ji U_i,  so  ||E_j||_inf <= sum_{i>r} sigma_i  and  ||E_j||_2 <= (sum_{i>r} sigma_i^2)^1/2
// (|V_ji| <= 1 and ||U_i||_inf <= ||U_i||_2 = 1). The rank is the smallest r whose bound meets a
// tolerance in the snapshots' own unit (mm): the seed's criterion looks at the singular values
// dropped, not at a ratio of those kept. Shared by the distortion model and the blank-deviation
// family (seed chapter 2).
#include <Eigen/Core>

namespace drom::reduce {

enum class PodNorm { Max, Euclidean };  // the norm whose bound the tolerance applies to

struct Pod {
  Eigen::MatrixXd modes;           // rows x r, orthonormal columns (U_r)
  Eigen::VectorXd singular_values; // all of them, descending
  Eigen::MatrixXd right;           // snapshots x r (V_r)
  double max_bound = 0;            // sum_{i>r} sigma_i
  double euclidean_bound = 0;      // (sum_{i>r} sigma_i^2)^1/2
  int rank() const { return static_cast<int>(modes.cols()); }
};

// The bounds for keeping r modes of these singular values.
double max_norm_bound(const Eigen::VectorXd& singular_values, int r);
double euclidean_bound(const Eigen::VectorXd& singular_values, int r);

// POD of the columns of `snapshots`, with the fewest modes whose bound (in `norm`) is <= tolerance,
// and at most max_rank modes (-1: no cap; the bound then reports what the cap costs).
// Thin SVD through a Householder QR first, so a tall matrix (millions of rows, tens of columns)
// costs one pass over it and the small singular values keep their accuracy.
Pod truncated_pod(const Eigen::MatrixXd& snapshots, double tolerance, PodNorm norm = PodNorm::Max, int max_rank = -1);

}  // namespace drom::reduce
