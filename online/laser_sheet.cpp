#include "online/laser_sheet.hpp"

#include <cmath>
#include <limits>

namespace drom::online {

std::vector<Eigen::Vector2d> LaserSheet::footprint(const Eigen::Vector3d& tip) const {
  const double a = angle_deg * M_PI / 180;
  const Eigen::Vector2d centre = tip.head<2>() + offset.head<2>(), d(std::cos(a), std::sin(a));
  std::vector<Eigen::Vector2d> p;
  p.reserve(static_cast<std::size_t>(points));
  for (int i = 0; i < points; ++i) p.push_back(centre + d * (length * (points > 1 ? static_cast<double>(i) / (points - 1) - 0.5 : 0.0)));
  return p;
}

std::vector<MeasuredPoint> scan(const LaserSheet& calibrated, const SensorErrors& errors, const Eigen::Vector3d& believed_tip, const Eigen::Vector3d& true_tip,
                                const HeightField& surface, std::mt19937& rng) {
  LaserSheet actual = calibrated;
  actual.offset += errors.offset_error;
  actual.angle_deg += errors.angle_error_deg;
  const auto believed = calibrated.footprint(believed_tip), truth = actual.footprint(true_tip);
  const double emitter_z = true_tip.z() + actual.offset.z();
  std::normal_distribution<double> noise(0, errors.noise_sd > 0 ? errors.noise_sd : 1);
  std::vector<MeasuredPoint> out;
  out.reserve(believed.size());
  for (std::size_t i = 0; i < believed.size(); ++i) {
    const auto z = surface(truth[i].x(), truth[i].y());
    double reading = std::numeric_limits<double>::quiet_NaN();
    if (z && std::isfinite(*z) && emitter_z - *z <= actual.range && emitter_z > *z) reading = *z + (errors.noise_sd > 0 ? noise(rng) : 0.0);
    out.push_back({believed[i].x(), believed[i].y(), reading});
  }
  return out;
}

}  // namespace drom::online
