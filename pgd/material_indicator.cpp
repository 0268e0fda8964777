#include "pgd/material_indicator.hpp"

#include "fem/elastic_problem.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace drom::pgd {

double MaterialIndicator::value(int plane_element, int thickness_element) const {
  double v = 1;
  for (std::size_t m = 0; m < removed_plane.size(); ++m) v -= removed_plane[m][plane_element] * removed_thickness[m][thickness_element];
  return v;
}

MaterialIndicator MaterialIndicator::intact() { return {}; }

MaterialIndicator MaterialIndicator::flat_bottom(const TensorGrid& grid, const Eigen::VectorXd& plane_fraction, double floor_t) {
  if (plane_fraction.size() != grid.plane_elements()) throw std::invalid_argument("flat_bottom: one fraction per plane element");
  MaterialIndicator ind;
  Eigen::VectorXd h(grid.nt);
  for (int k = 0; k < grid.nt; ++k) {
    const double lo = grid.levels[static_cast<std::size_t>(k)], hi = grid.levels[static_cast<std::size_t>(k + 1)];
    h[k] = std::clamp((hi - floor_t) / (hi - lo), 0.0, 1.0);
  }
  if (plane_fraction.cwiseAbs().maxCoeff() > 0 && h.maxCoeff() > 0) {
    ind.removed_plane.push_back(plane_fraction);
    ind.removed_thickness.push_back(h);
  }
  return ind;
}

MaterialIndicator MaterialIndicator::from_activity(const TensorGrid& grid, const std::vector<double>& activity, double tolerance) {
  const int ne = grid.plane_elements(), nt = grid.nt;
  if (static_cast<int>(activity.size()) != ne * nt) throw std::invalid_argument("from_activity: one fraction per tensor element");
  Eigen::MatrixXd removed(ne, nt);
  for (int k = 0; k < nt; ++k)
    for (int e = 0; e < ne; ++e) removed(e, k) = 1.0 - activity[static_cast<std::size_t>(grid.element(e, k))];
  MaterialIndicator ind;
  if (removed.cwiseAbs().maxCoeff() == 0) return ind;
  Eigen::BDCSVD<Eigen::MatrixXd> svd(removed, Eigen::ComputeThinU | Eigen::ComputeThinV);
  Eigen::MatrixXd approx = Eigen::MatrixXd::Zero(ne, nt);
  for (Eigen::Index m = 0; m < svd.singularValues().size(); ++m) {
    const double s = svd.singularValues()[m];
    if (s == 0) break;
    ind.removed_plane.push_back(s * svd.matrixU().col(m));
    ind.removed_thickness.push_back(svd.matrixV().col(m));
    approx += ind.removed_plane.back() * ind.removed_thickness.back().transpose();
    ind.truncation_error = (removed - approx).cwiseAbs().maxCoeff();
    if (ind.truncation_error <= tolerance) break;
  }
  return ind;
}

std::vector<double> effective_activity(std::vector<double> activity) {
  for (double& a : activity)
    if (a < fem::ElasticProblem::kMinVolumeFraction) a = 0;
  return activity;
}

}  // namespace drom::pgd
