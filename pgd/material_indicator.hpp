#pragma once
// The material indicator in separated form (docs/design.md §4, eq. D.14): the remaining volume fraction of
// each tensor element (plane element e, thickness element k) written as
//   I(e, k) = 1 - sum_m removed_plane[m](e) * removed_thickness[m](k).
// A flat-bottom pocket machined by a flat end mill is exactly one removed term (two in all, with the
// intact 1); other removal shapes take a truncated SVD of the removed fraction, and the truncation
// error is reported.
#include "pgd/tensor_grid.hpp"

#include <Eigen/Core>

#include <vector>

namespace drom::pgd {

struct MaterialIndicator {
  std::vector<Eigen::VectorXd> removed_plane;      // per plane element
  std::vector<Eigen::VectorXd> removed_thickness;  // per thickness element
  double truncation_error = 0;                     // max over elements of |I - its separated form|

  int terms() const { return 1 + static_cast<int>(removed_plane.size()); }
  // Remaining fraction of element (e, k) as represented.
  double value(int plane_element, int thickness_element) const;

  static MaterialIndicator intact();
  // Exact two-term form of a flat-bottom pocket: plane_fraction(e) is the removed fraction of the
  // element's footprint, and everything of that footprint above floor_t is gone.
  static MaterialIndicator flat_bottom(const TensorGrid& grid, const Eigen::VectorXd& plane_fraction, double floor_t);
  // From per-element remaining fractions in the Hex27 element order (grid.element(e, k)): truncated
  // SVD of the removed fraction, terms added until the largest element error is below tolerance.
  static MaterialIndicator from_activity(const TensorGrid& grid, const std::vector<double>& activity, double tolerance);
};

// The remaining fractions a fem::ElasticProblem would use: below its threshold an element is removed.
std::vector<double> effective_activity(std::vector<double> activity);

}  // namespace drom::pgd
