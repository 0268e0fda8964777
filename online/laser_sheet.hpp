#pragma once
// The laser-sheet sensor (docs/design.md §7; seed §2.2.3.2, §2.3.2, §3.5.1), as the closed loop and the
// blank-deviation identification simulate it. The sensor is fixed to the spindle head: its emission
// point is offset from the tool tip in the machine frame, and its sheet meets the part along a
// segment at a fixed angle to the machine's x axis (the main feed direction). Each of the sheet's
// points reads the height of whatever surface lies under it.
//
// What it reports is where it *believes* it measured: the believed tool tip (from synchronization)
// plus the calibrated geometry. The heights come from where it actually measured: the true tip plus
// the true geometry (calibration errors in offset and angle). Points with nothing under them, or
// farther than the sensor's range, come back as NaN, as a real sensor's "no reading".
#include "online/predictor.hpp"

#include <Eigen/Core>

#include <functional>
#include <optional>
#include <random>
#include <vector>

namespace drom::online {

struct LaserSheet {
  Eigen::Vector3d offset{50, 0, 80};  // emission point from the tool tip, machine frame (mm)
  double angle_deg = 90;              // the sheet's direction to the machine x axis
  double length = 80;                 // mm
  int points = 800;
  double range = 200;                 // mm below the emission point beyond which nothing is read
  // The sheet's points in the machine's xy plane for a tool tip (centred on the emission point).
  std::vector<Eigen::Vector2d> footprint(const Eigen::Vector3d& tip) const;
};

struct SensorErrors {
  Eigen::Vector3d offset_error = Eigen::Vector3d::Zero();  // true offset - calibrated offset (mm)
  double angle_error_deg = 0;                              // true angle - calibrated angle
  double noise_sd = 0;                                     // Gaussian noise on each height (mm)
};

// Height of the surface at (x, y), or nothing where there is no part.
using HeightField = std::function<std::optional<double>(double x, double y)>;

// One profile: points at the calibrated sheet's positions for believed_tip, heights read at the true
// sheet's positions for true_tip, plus noise.
std::vector<MeasuredPoint> scan(const LaserSheet& calibrated, const SensorErrors& errors, const Eigen::Vector3d& believed_tip, const Eigen::Vector3d& true_tip,
                                const HeightField& surface, std::mt19937& rng);

}  // namespace drom::online
