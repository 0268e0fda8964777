#pragma once
// What a noise-free laser reads on the machined floor (docs/design.md §6, online/machined_floor.hpp):
// where the tool covered (x, y) at times tau with offset o(tau), the floor is the lowest cut in the
// material's frame, S0 + min over tau of (o(tau) - w(x, y, tau)), moved by w(x, y, t) since. Brute
// force, independent of the predictor's and the simulator's own searches: every cover's ends, the
// offset changes and given instants inside it, and 64 samples across it.
#include "reduce/cut_time.hpp"
#include "reduce/light_model.hpp"

#include <Eigen/Core>

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <vector>

namespace drom::test {

class ExactReading {
 public:
  // w(point, tau): the truth's displacement; offset: the step function of the offsets in force,
  // changing at `offset_changes`; `instants`: where w has kinks (the stations).
  ExactReading(const reduce::LightModel& m, std::function<double(const reduce::SurfacePoint&, double)> w, std::function<double(double)> offset,
               std::vector<double> offset_changes, std::vector<double> instants)
      : m_(m), covers_(m.path, m.tool_radius, 0.02 * m.pocket_depth, 1e300), w_(std::move(w)), offset_(std::move(offset)),
        changes_(std::move(offset_changes)), instants_(std::move(instants)) {}

  // NaN where the tool has not cut (or off the target).
  double operator()(double x, double y, double t) const {
    const auto p = m_.target.locate(x, y);
    if (!p) return std::nan("");
    const double s0 = m_.target.nominal_altitude(*p);
    std::vector<std::pair<double, double>> covers;
    covers_.covers({x, y, s0}, t, covers);
    if (covers.empty()) return std::nan("");
    double lowest = std::numeric_limits<double>::infinity();
    for (const auto& [a, b] : covers) {
      std::vector<double> taus = {a, b};
      for (int k = 1; k < 64; ++k) taus.push_back(a + (b - a) * k / 64.0);
      for (double c : instants_)
        if (c > a && c < b) taus.push_back(c);
      for (double c : changes_)
        if (c > a && c < b) taus.push_back(c), taus.push_back(std::nextafter(c, -1e300));
      for (double tau : taus) lowest = std::min(lowest, offset_(tau) - w_(*p, tau));
    }
    return s0 + lowest + w_(*p, t);
  }

 private:
  const reduce::LightModel& m_;
  reduce::CutTimeIndex covers_;
  std::function<double(const reduce::SurfacePoint&, double)> w_;
  std::function<double(double)> offset_;
  std::vector<double> changes_, instants_;
};

}  // namespace drom::test
