#pragma once
// Analytic finishing times of inclined rectangular planes (Herraz ch. 2, Annexes A and E): the
// torus along the slope (T1, eq. 2.4) and the ball along the principal direction (T2, eq. 2.5), the
// critical slope s_c(mu) where they tie (Cardan, eqs. 2.6-2.10) and the critical shape factor
// mu_c(s) (Annex A, eq. 8), the ball-or-torus verdict on a PCA plane (§2.4.1), and the time of a
// rectangle fed at any angle (Annex E, the seed's surrogate S3). Passes reach the feed and links do
// not (the seed's case 2 and case 3), as the seed assumes.
#include "paths/finish/move_time.hpp"
#include "paths/finish/pca.hpp"
#include "paths/cutter/tool.hpp"

#include <string>

namespace drom::paths {

struct PlaneTime {
  double time = 0, length = 0;  // s, mm
  double stepover = 0;          // mm
  double passes = 0;            // the seed's real-valued count (width / step-over)
};

// The rectangle: `width` horizontal along the principal direction, `height` along the slope, at
// `slope` radians. T1/L1: the torus along the slope. T2/L2: the ball along the principal direction.
PlaneTime torus_along_slope(double width, double height, double slope, const Tool& torus, double scallop, const Kinematics& k);
PlaneTime ball_along_principal(double width, double height, const Tool& ball, double scallop, const Kinematics& k);

// The slope at which T1 = T2 for a rectangle of shape factor mu and size chi (mm^2): eq. 2.10 with
// the real root of eq. 2.6 by Cardan's formula (eq. 2.9, with +q). pi/2 when the torus wins at any
// slope.
double critical_slope(double shape_factor, double size, const Tool& torus, const Tool& ball, double scallop, const Kinematics& k);
// The shape factor at which T1 = T2 at a given slope (Annex A, eq. 8); 1 when the ball already wins
// on a square.
double critical_shape_factor(double slope, double size, const Tool& torus, const Tool& ball, double scallop, const Kinematics& k);

struct ToolVerdict {
  bool ball = false;            // the ball along the principal direction, else the torus along the slope
  double critical_slope = 0;    // s_c(mu~)
  double critical_shape = 0;    // mu_c(s~)
  PlaneTime torus, ball_time;   // T1 and T2 on the fitted rectangle
  double feed_azimuth = 0;      // the chosen feed direction's azimuth
  std::string reason;           // "s~ = 42.3 deg > s_c = 38.9 deg: ball along the principal direction"
};

// The procedure of §2.4.1 on a surface's or zone's PCA plane.
ToolVerdict choose_tool(const PcaPlane& plane, const Tool& torus, const Tool& ball, double scallop, const Kinematics& k);

// Annex E: the time to finish the fitted rectangle (w along X_I, h along X_II) with passes at
// `alpha` to X_I (radians, folded into [0, pi/2]) a constant `stepover` apart; real-valued pass counts.
double rectangle_time(double width, double height, double alpha, double stepover, const Kinematics& k);

// The seed's surrogate S3 for a zone fed along the horizontal azimuth `theta`: the feed projected
// into the PCA plane, alpha its angle to X_I, the step-over from eq. 1.5 at the plane's slope and the
// feed's angle to the plane's steepest direction (capped by the level-ground step), then Annex E.
double pca_plane_time(const PcaPlane& plane, double theta, const Tool& tool, double scallop, const Kinematics& k);

}  // namespace drom::paths
