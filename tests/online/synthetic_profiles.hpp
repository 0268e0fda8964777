#pragma once
// Laser profiles of the synthetic model (tests/reduce/synthetic_model.hpp) as a noise-free or noisy
// sensor would read them (tests/online/exact_reading.hpp), for the predictor's tests.
#include "online/predictor.hpp"
#include "tests/online/exact_reading.hpp"

#include <Eigen/Core>

#include <cmath>
#include <functional>
#include <random>
#include <vector>

namespace drom::test {

// Program time -> tool tip on the synthetic path (linear between waypoints).
inline Eigen::Vector3d tool_at(const reduce::LightModel& m, double t) {
  const Eigen::VectorXd times = m.path.col(3);
  const auto [i, w] = reduce::locate_time(times, t);
  return ((1 - w) * m.path.row(i).head<3>() + w * m.path.row(i + 1).head<3>()).transpose();
}

// What the sensor reads for coefficients alpha (tests/online/exact_reading.hpp), w written with the
// model's own fields, the offsets applied so far a step function of time. One reader serves many
// points: it indexes the whole path's covers once.
class SyntheticReading {
 public:
  SyntheticReading(const reduce::LightModel& m, const Eigen::VectorXd& alpha, const std::function<double(double)>& offset)
      : exact_(m, [&m, alpha](const reduce::SurfacePoint& p, double tau) { return w(m, alpha, p, tau); }, offset, {30, 60}, instants(m)) {}

  double operator()(double x, double y, double t) const { return exact_(x, y, t); }

 private:
  static double w(const reduce::LightModel& m, const Eigen::VectorXd& alpha, const reduce::SurfacePoint& p, double tau) {
    double v = 0;
    for (int q = 0; q < p.count; ++q)
      for (int k = 0; k < m.rank(); ++k)
        v += alpha[k] * p.weights[static_cast<std::size_t>(q)] * m.histories[static_cast<std::size_t>(k)].at(p.nodes[static_cast<std::size_t>(q)], tau);
    return v;
  }
  static std::vector<double> instants(const reduce::LightModel& m) {
    const Eigen::VectorXd& times = m.histories.front().times();
    return {times.data(), times.data() + times.size()};
  }
  test::ExactReading exact_;  // the offsets step at 30 and 60 s in the tests' offset functions
};

// What the sensor reads at one point (x, y) and time t.
inline double reading(const reduce::LightModel& m, const Eigen::VectorXd& alpha, double x, double y, double t, const std::function<double(double)>& offset) {
  return SyntheticReading(m, alpha, offset)(x, y, t);
}

// A profile across the feed, 30 mm behind the tool, 80 mm long, of `count` points (the seed's 800).
inline std::vector<online::MeasuredPoint> profile(const reduce::LightModel& m, const Eigen::VectorXd& alpha, double t, double noise, std::mt19937& rng,
                                                  const std::function<double(double)>& offset, int count = 800) {
  const Eigen::Vector3d tool = tool_at(m, t);
  const SyntheticReading read(m, alpha, offset);
  std::normal_distribution<double> gauss(0, noise);
  std::vector<online::MeasuredPoint> pts;
  for (int i = 0; i < count; ++i) {
    const double x = tool.x() - 30, y = tool.y() - 40 + 80.0 * i / (count - 1);
    const double z = read(x, y, t);
    pts.push_back({x, y, std::isnan(z) ? z : z + (noise > 0 ? gauss(rng) : 0)});
  }
  return pts;
}

inline std::vector<double> profile_times() {
  std::vector<double> t;
  for (int p = 0; p < 5; ++p)
    for (int k = 1; k <= 10; ++k) t.push_back(p * 25.0 + 2.0 * k - 0.5);  // during each pass's cutting
  return t;
}

}  // namespace drom::test
