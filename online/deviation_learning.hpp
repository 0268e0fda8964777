#pragma once
// The learning phase of the blank-deviation identification (seed §2.2.4.6, §2.3.3): laser profiles
// taken along the approach and the first moves, until the fit can be trusted to correct the tool's
// altitude before it gets there. Two criteria, both needed:
//   - offline, the scan extent: each deviation mode in turn is taken as the true surface, the
//     approach is scanned (noise-free), and the program time after which the fit is within the
//     tolerance along the cutting path is found; the worst mode's is the extent needed;
//   - online, the residual: the recent profiles are predicted, before being added, within the
//     tolerance net of the sensor's noise.
#include "online/dead_reckoning.hpp"
#include "online/deviation_identifier.hpp"
#include "online/laser_sheet.hpp"

#include <Eigen/Core>

#include <random>
#include <vector>

namespace drom::online {

// Profiles every `period` of program time along a path (x, y, z, program time), the tool where the
// program has it; the sensor reads `surface`.
struct ScanPlan {
  Eigen::MatrixXd path;
  double period = 0.1;
  LaserSheet sheet;
  SensorErrors errors;
  std::vector<double> profile_times(double until) const;
  Eigen::Vector3d tool_at(double t) const { return path_position(path, t); }
};

struct ScanExtent {
  double program_time = 0;           // the extent needed: the worst mode's
  std::vector<double> per_mode_time;  // +inf: that mode is never identified within the tolerance on this scan
};

// The offline criterion. modes: grid points x r; amplitude_k scales mode k to the largest it appears
// in the family (mm); check: where the fit must be right (the cutting path's points).
ScanExtent needed_scan_extent(const reduce::DeviationGrid& grid, const Eigen::MatrixXd& modes, const Eigen::VectorXd& amplitudes, const ScanPlan& plan,
                              double until, double tolerance, const std::vector<Eigen::Vector2d>& check);

// The online criterion, profile by profile.
class LearningMonitor {
 public:
  LearningMonitor(double tolerance, double noise_sd, int window) : tolerance_(tolerance), noise_sd_(noise_sd), window_(window) {}
  // Adds a profile's points to the identifier, after predicting them with the fit so far; true once
  // the last `window` profiles were predicted within the tolerance (net of noise).
  bool add(DeviationIdentifier& id, std::span<const MeasuredPoint> points);
  bool learned() const { return learned_; }
  double last_predictive_rms() const { return last_rms_; }

 private:
  double tolerance_, noise_sd_;
  int window_;
  std::vector<double> recent_;  // net predictive RMS of recent profiles
  bool learned_ = false;
  double last_rms_ = 0;
};

}  // namespace drom::online
