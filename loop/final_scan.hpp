#pragma once
// The unclamped part scanned by the loop's own laser sheet, and the final-shape basis fitted to the
// scan (issue 45 item 8: `drom run --replan` from the laser's points, beside the model's prediction).
//
// Why a scan after unclamping: the laser reads the part while it is clamped and being cut; every
// profile shows the part as it was at that instant, before the later passes and before the clamps
// let go. The finish is re-planned for the unclamped part, so the points it is planned from have to
// be read off that part: once unclamped and lying on its isostatic supports, the part is swept by
// the same sensor (same sheet, same noise, same calibration errors), strip by strip along x.
//
// Why a fit and not the raw points: the sensor's noise (0.05 mm in the seed) is two orders of
// magnitude above the distortion's prediction error (microns); a ball dropped on the raw points
// stands on their highest noise. The scan's million points are fitted by the model's final-shape
// basis U2 (the same r columns the online predictor uses), by least squares in the heights: each
// point's height is the displaced surface's at its (x, y), with the in-plane displacement taken into
// account through the surface's slope (a bent plate's top slides along itself by its half thickness
// times its slope; ignored, that is microns of height). Gauss-Newton, the points relocated on the
// displaced faces at each iteration; from the third iteration on, points farther from the fit than
// `outlier_sigmas` robust deviations (1.4826 x the residuals' median absolute value) are left out (a
// chip, a reflection). Alone, the scan determines alpha; with the loop's estimate as a prior
// (fit_final_shape below), it updates it.
#include "online/laser_sheet.hpp"
#include "online/predictor.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <vector>

namespace drom::loop {

// The displaced upward faces of a final shape as a height field: the highest upward face over (x, y)
// (bilinear in each quad, linear in each triangle, from the corners of quadratic faces, as
// loop/replanned_finish's upward_surface_cloud samples them; the faces whose outward normal is within
// acos(min_up) of +Z), nothing off the part. A mesh wound inward has no upward face: the fit then
// says it has no usable point.
online::HeightField upward_height_field(const online::FinalShape& shape, const Eigen::Matrix3Xd& displacement, double min_up = 0.9);

struct FinalScanSettings {
  double step = 0.5;             // mm between profiles along x
  double clearance = 5;          // mm: the tool tip's height above the part's highest point while scanning
  double min_up = 0.9;           // upward faces, as the re-planned finish's
  int iterations = 4;            // Gauss-Newton iterations (relocation on the displaced faces)
  double outlier_sigmas = 6;     // a point this many robust deviations off the fit is left out
  std::uint32_t seed = 2016;     // the scan's noise draw
};

struct FinalScan {
  std::vector<online::MeasuredPoint> points;  // what the sensor returned (no-readings dropped)
  long long profiles = 0, no_reading = 0;
};

// Sweeps the sheet over the part whose surface is `surface` (believed = true tip: the scan is a
// programmed sweep; the sensor's calibration errors and noise are `errors`), covering `lo`..`hi` in xy.
FinalScan scan_final_part(const online::HeightField& surface, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, double top, const online::LaserSheet& sheet,
                          const online::SensorErrors& errors, const FinalScanSettings& settings);

struct ScanFit {
  Eigen::VectorXd alpha;            // the final-shape basis's coefficients
  Eigen::MatrixXd covariance;       // of alpha, from the residuals
  online::FinalShape shape;         // the fitted final shape (displacement U2 alpha, its sd)
  long long used = 0, off_part = 0, outliers = 0;  // in the last iteration
  double residual_rms = 0;          // mm, of the points used (the sensor's noise when the basis holds the part)
  int iterations = 0;
  int unobserved = 0;               // directions of alpha neither the scan nor the prior determines (left out of the covariance)
};

// `geometry`: the final part's surface (its nodes and faces; displacement ignored); `final_basis`:
// U2, (3 x nodes) x r, rows (node, component).
//
// Without a prior, the scan alone determines alpha (least squares; its covariance from the residual
// RMS). With one (the online predictor's estimate at the end of the cut: what the loop's laser read
// while the part was clamped), the scan updates it: the posterior of both, the scan's heights with
// standard deviation `noise_sd`, so every point the laser read, in the loop and after unclamping,
// weighs in. Throws std::invalid_argument when the scan has fewer usable points than the basis has
// columns (and no prior), or when the sizes disagree.
struct ScanPrior {
  Eigen::VectorXd mean;
  Eigen::MatrixXd covariance;
  double noise_sd = 0.05;  // mm: the scan's heights (the sensor's noise)
};
ScanFit fit_final_shape(const online::FinalShape& geometry, const Eigen::MatrixXd& final_basis, const std::vector<online::MeasuredPoint>& points,
                        const FinalScanSettings& settings = {}, const ScanPrior* prior = nullptr);

// The largest distance between two displacements of the final part over its upward faces' corner
// nodes (mm): how far a fitted or predicted shape is from the truth where the finish runs.
double max_upward_difference(const online::FinalShape& geometry, const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b, double min_up = 0.9);

}  // namespace drom::loop
