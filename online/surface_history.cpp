#include "online/surface_history.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace drom::online {

SurfaceHistory::SurfaceHistory(const reduce::SurfaceMesh& mesh, Eigen::MatrixXd values, Eigen::VectorXd times, double start) : mesh_(&mesh) {
  if (values.rows() != mesh.node_count() || values.cols() != times.size() || times.size() == 0)
    throw std::invalid_argument("SurfaceHistory: values must be surface nodes x stations");
  for (Eigen::Index k = 0; k < times.size(); ++k)
    if (!(times[k] > (k == 0 ? start : times[k - 1]))) throw std::invalid_argument("SurfaceHistory: station times must increase after the start");
  values_.resize(values.rows(), values.cols() + 1);
  values_.col(0).setZero();
  values_.rightCols(values.cols()) = values;
  times_.resize(times.size() + 1);
  times_ << start, times;
}

const Eigen::VectorXd& SurfaceHistory::nodal(double t) const {
  if (t == cached_t_) return cached_;
  cached_t_ = t;
  const Eigen::Index n = times_.size();
  if (t <= times_[0]) cached_ = values_.col(0);
  else if (t >= times_[n - 1]) cached_ = values_.col(n - 1);
  else {
    const auto hi = static_cast<Eigen::Index>(std::upper_bound(times_.data(), times_.data() + n, t) - times_.data());
    const double f = (t - times_[hi - 1]) / (times_[hi] - times_[hi - 1]);
    cached_ = (1 - f) * values_.col(hi - 1) + f * values_.col(hi);
  }
  return cached_;
}

double SurfaceHistory::at(const reduce::SurfacePoint& p, double t) const { return mesh_->interpolate(p, nodal(t))[0]; }

double SurfaceHistory::at_instant(const reduce::SurfacePoint& p, double t) const { return at_instant(p, reduce::locate_time(times_, t)); }

double SurfaceHistory::at_instant(const reduce::SurfacePoint& p, const reduce::TimeInterval& at) const {
  const Eigen::Index next = at.i + 1;  // times_ holds the start and at least one station
  double v = 0;
  for (int q = 0; q < p.count; ++q) {
    const int node = p.nodes[static_cast<std::size_t>(q)];
    v += p.weights[static_cast<std::size_t>(q)] * ((1 - at.weight) * values_(node, at.i) + at.weight * values_(node, next));
  }
  return v;
}

}  // namespace drom::online
