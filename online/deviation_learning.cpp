#include "online/deviation_learning.hpp"


#include <cmath>
#include <limits>

namespace drom::online {

std::vector<double> ScanPlan::profile_times(double until) const {
  std::vector<double> t;
  const double end = std::min(until, path(path.rows() - 1, 3));
  for (double s = path(0, 3); s <= end + 1e-12; s += period) t.push_back(s);
  return t;
}



ScanExtent needed_scan_extent(const reduce::DeviationGrid& grid, const Eigen::MatrixXd& modes, const Eigen::VectorXd& amplitudes, const ScanPlan& plan,
                              double until, double tolerance, const std::vector<Eigen::Vector2d>& check) {
  ScanExtent extent;
  const auto times = plan.profile_times(until);
  for (Eigen::Index k = 0; k < modes.cols(); ++k) {
    const Eigen::VectorXd truth = amplitudes[k] * modes.col(k);
    auto value = [&](double x, double y) {
      double v = 0;
      for (const auto& [i, w] : grid.weights(x, y)) v += w * truth[i];
      return v;
    };
    const HeightField surface = [&](double x, double y) -> std::optional<double> {
      if (!grid.contains(x, y)) return std::nullopt;
      return value(x, y);
    };
    DeviationIdentifier id(grid, modes);
    std::mt19937 rng(0);
    double found = std::numeric_limits<double>::infinity();
    for (double t : times) {
      const Eigen::Vector3d tip = plan.tool_at(t);
      id.add_points(scan(plan.sheet, {}, tip, tip, surface, rng));
      if (id.points() == 0) continue;
      const Eigen::VectorXd c = id.coefficients();
      double e = 0;
      for (const auto& p : check) e = std::max(e, std::abs(id.deviation(p.x(), p.y(), c) - value(p.x(), p.y())));
      if (e <= tolerance) {
        found = t;
        break;
      }
    }
    extent.per_mode_time.push_back(found);
    extent.program_time = std::max(extent.program_time, found);
  }
  return extent;
}

bool LearningMonitor::add(DeviationIdentifier& id, std::span<const MeasuredPoint> points) {
  // Predict the new points with the fit from the earlier ones, then add them.
  const Eigen::VectorXd c = id.coefficients();
  double se = 0;
  int n = 0;
  for (const auto& p : points) {
    if (!std::isfinite(p.z)) continue;
    const double e = p.z - id.altitude(p.x, p.y, c);
    se += e * e, ++n;
  }
  const bool had_data = id.points() > 0;
  id.add_points(points);
  if (n == 0 || !had_data) return learned_;
  last_rms_ = std::sqrt(se / n);
  recent_.push_back(std::sqrt(std::max(0.0, last_rms_ * last_rms_ - noise_sd_ * noise_sd_)));
  if (static_cast<int>(recent_.size()) > window_) recent_.erase(recent_.begin());
  bool all = static_cast<int>(recent_.size()) == window_;
  for (double r : recent_) all = all && r <= tolerance_;
  learned_ = learned_ || all;
  return learned_;
}

}  // namespace drom::online
