#pragma once
// Tool-axis orientation relaxed under the machine's kinematic limits (Lavernhe et al. 2007 §3-4,
// eq. 5): the guide surface S1 = S + r n is kept, so the part's geometry is, and the orientation
// surface S2 = S1 + (R - r) v deforms: the tilt θt(s) (and, optionally, the yaw θn(s)) along each
// pass become uniform cubic B-splines whose control values minimize the pass's predicted time on
// the machine (machine/feed_prediction.hpp) within bounds.
//
// The seed writes eq. 5 and calls it unsolvable explicitly; it only shows a manual deformation (5°
// imposed at a few points of a C-saturated zone). Here the problem is solved per pass with NLopt's
// BOBYQA: derivative-free (the predicted time is piecewise smooth in the tilt, with kinks where the
// limiting axis changes), bound-constrained (the B-spline's control values bound the tilt everywhere,
// by its convex hull), and economical in evaluations (each one is an inverse kinematics and a feed
// prediction of the pass), for the handful of variables a pass needs. Among equally fast tilts the
// one nearest the programmed orientation is kept (a regularization worth 1 ms per rad² of deviation).
// The consequences are reported per point: the effective radius across the feed (Herraz eq. 1.5,
// Redonnet 2013), the scallop it leaves at the step-over on flat ground, and the gouge margin against
// the surface's concave curvature across the feed.
#include "machine/feed_prediction.hpp"
#include "machine/kinematics.hpp"
#include "paths/cutter/stepover.hpp"

#include <Eigen/Core>

#include <vector>

namespace drom::paths {

// A point of a pass on the part's surface S.
struct PassPoint {
  Eigen::Vector3d contact = Eigen::Vector3d::Zero();      // on S, part frame (mm)
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();      // unit, out of the material
  Eigen::Vector3d feed = Eigen::Vector3d::UnitX();        // unit tangent along the pass, normal to `normal`
  double cross_curvature = 0;  // normal curvature of S across the feed (1/mm), positive where S is concave (bends towards the tool)
};

struct SurfacePass {
  std::vector<PassPoint> points;
  double feed = 1000;  // mm/min
};

// Tilt θt from the normal towards d = cos θn f + sin θn (n × f) (θn = 0: lead along the feed).
struct Orientation {
  double tilt = 0, yaw = 0;  // rad
};

// The tool pose for a surface point (the tool a torus, or a ball: r = R): the corner circle's centre on the guide surface S1 = C + r n,
// the axis a = cos θt n + sin θt d, the tool tip T = S1 + (R - r) v - r a with v = sin θt n - cos θt d.
machine::ClPose tool_pose(const PassPoint& p, const Tool& tool, const Orientation& o);
// The effective radius across the feed (Herraz eq. 1.5, paths/cutter/stepover.hpp, with the tilt as
// the slope s and the yaw as α); infinite for a torus without tilt. The scallop it leaves at a
// step-over on flat ground is flat_scallop(stepover, radius).
double effective_radius(const Tool& tool, const Orientation& o);

struct RelaxationSettings {
  double tilt_min = 1 * 3.14159265358979323846 / 180, tilt_max = 5 * 3.14159265358979323846 / 180;  // rad
  bool free_yaw = false;          // also optimize the yaw field (within ± yaw_range of the programmed yaw)
  double yaw_range = 3.14159265358979323846 / 2;
  int control_points = 12;        // per field and pass
  double stepover = 8;            // mm between passes (for the scallop report)
  int max_evaluations = 400;      // per pass
};

struct PassOrientation {
  std::vector<Orientation> orientation;  // per point
  std::vector<machine::ClPose> poses;    // per point
  double time_before = 0, time_after = 0;  // s, predicted on the machine
  std::vector<double> effective_radius, scallop, gouge_margin;  // per point (mm); gouge margin = 1/κ - R_eff where concave, else +∞
  int evaluations = 0;
};

// The programmed orientation `programmed` along each point, relaxed; throws InputError when a pose is
// out of the machine's reach at every admissible tilt.
PassOrientation relax_orientation(const SurfacePass& pass, const Tool& tool, const std::vector<Orientation>& programmed,
                                  const machine::Kinematics& kinematics, const RelaxationSettings& settings);

// The pass's predicted time on the machine for given orientations (one per point).
double pass_time(const SurfacePass& pass, const Tool& tool, const std::vector<Orientation>& orientation, const machine::Kinematics& kinematics);

}  // namespace drom::paths
