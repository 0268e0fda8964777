#pragma once
// Milling tools as solids of revolution (flat, ball and bull-nose end mills) and their signed
// distance. Every one is the Minkowski sum of a core rectangle with a disc of the corner radius,
// in the (rho, h) half-plane (rho from the axis, h above the tip), cut flat at the flute length.
#include <Eigen/Core>

namespace drom::levelset {

enum class ToolKind { Flat, Ball, BullNose };

struct Tool {
  ToolKind kind = ToolKind::Flat;
  double radius = 10;         // R, mm
  double corner_radius = 0;   // r: 0 flat, R ball, (0, R) bull-nose
  double flute_length = 30;   // cutting height above the tip, mm

  static Tool flat(double radius, double flute_length);
  static Tool ball(double radius, double flute_length);
  static Tool bull_nose(double radius, double corner_radius, double flute_length);

  // Radius of the tool's section at height h above the tip (0 below the tip or above the flutes).
  double section_radius(double h) const;
  // Height of the tool's lower surface above the tip at distance rho from the axis (rho <= R).
  double bottom_height(double rho) const;
  // Signed distance (negative inside) in the (rho, h) half-plane.
  double signed_distance(double rho, double h) const;
};

// Where the tool is: its tip and its axis (unit, pointing from the tip into the holder).
struct ToolPose {
  Eigen::Vector3d tip = Eigen::Vector3d::Zero();
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
};

double signed_distance(const Tool& tool, const ToolPose& pose, const Eigen::Vector3d& x);

// Signed distance to the volume the tool sweeps while its tip moves along the segment a -> b at
// constant axis: min over the segment of the tool's distance (exact at the surface, convex tools).
// `tolerance` bounds the search along a segment that is not perpendicular to the axis (mm).
double swept_signed_distance(const Tool& tool, const Eigen::Vector3d& axis, const Eigen::Vector3d& a, const Eigen::Vector3d& b,
                             const Eigen::Vector3d& x, double tolerance = 1e-6);

}  // namespace drom::levelset
