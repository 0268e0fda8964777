#pragma once
// The cutter: an end mill as a solid of revolution about its axis, in the (rho, h) half-plane (rho
// from the axis, h above the tip). Every end mill drom knows is a torus: a disc of radius R - r on
// the tip plane grown by the corner radius r, so a ball is r = R and a flat end mill r = 0.
// This header owns what every user of a cutter shares: its lower profile h(rho) (the tool drop, the
// pocket's contact), the contact-to-tool offset (the CL point of a contact with a given normal) and
// the pivot; tool_assembly.hpp adds the flutes, shank and holder, and the signed distance.
#include <Eigen/Core>

#include <string>

namespace drom::paths {

enum class ToolKind { ball, torus };  // a flat end mill is a torus without corner; a bull-nose, a torus

struct Tool {
  ToolKind kind = ToolKind::ball;
  double radius = 5;         // R, mm
  double corner_radius = 5;  // r, mm (a ball: r = R; flat: 0)

  static Tool ball(double radius) { return {ToolKind::ball, radius, radius}; }
  static Tool torus(double radius, double corner_radius) { return {ToolKind::torus, radius, corner_radius}; }
  static Tool flat(double radius) { return {ToolKind::torus, radius, 0.0}; }

  std::string name() const;  // "ball R5", "torus R5 r2", "flat R3"
  // The pivot's height above the tip: the centre of the ball, or of the torus's corner circle, on
  // the axis (the point a 5-axis CL file and the orientation's frames place).
  double pivot_height() const { return corner_radius; }
};

bool is_flat(const Tool& cutter);

// The cutter's lower profile: the height above the tip of its lowest point at distance rho from the
// axis (|rho| <= R; beyond R, the corner's top, r).
double bottom_height(const Tool& cutter, double rho);

// The tool tip touching the surface at `cc` with the machined side's unit normal, the tool along
// `axis`: ball centre cc + R n, torus corner centre cc + r n moved (R - r) towards the axis; the tip
// is below it along the axis.
Eigen::Vector3d cutter_location(const Eigen::Vector3d& cc, const Eigen::Vector3d& normal, const Tool& tool, const Eigen::Vector3d& axis);

}  // namespace drom::paths
