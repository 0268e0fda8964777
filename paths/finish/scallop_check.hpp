#pragma once
// The material a finished path leaves, simulated without the step-over model: along the surface
// normal at each check point, the distance to the first place any tool position reaches (the tool's
// solid swept straight between consecutive tool-tip points of every pass). Positive: uncut material
// (the scallop height there); negative: the tool cut into the surface (a gouge). The bull-nose is
// the set of points within r of its swept centre disk (radius R - r, normal to the axis), the ball
// the same with a disk of radius 0: one exact model for both tools.
#include "geometry/nurbs_surface.hpp"
#include "paths/cutter/tool.hpp"
#include "paths/finish/zone_machining.hpp"

#include <Eigen/Core>

#include <vector>

namespace drom::paths {

struct ScallopCheck {
  int points = 0;            // check points inside the machined passes' reach
  double max_height = 0;     // mm, the largest uncut thickness along the normal
  double max_gouge = 0;      // mm (>= 0), the deepest cut below the surface
  Eigen::Vector2d worst_uv = Eigen::Vector2d::Zero();  // where max_height is
  std::vector<double> heights;  // per check point (row-major over the grid), NaN where no tool came within the window
};

// A straight tool move between two tool-tip positions (the tool's lowest point), its axis fixed; part frame.
struct ToolMove {
  Eigen::Vector3d tip0, tip1, axis;
};

// The same measure at any check points: per point, along its unit normal (out of the material), the
// distance to the first place the swept tool reaches; NaN where no tool came within `window` mm.
// Positive: uncut material; negative: a gouge. (Used on point clouds too: paths/copy/cloud_finishing.hpp.)
std::vector<double> envelope_heights(const std::vector<Eigen::Vector3d>& points, const std::vector<Eigen::Vector3d>& normals, const std::vector<ToolMove>& moves,
                                     const Tool& tool, double window);

// Check points on a grid of count_u x count_v over [u0, u1] x [v0, v1] (unit parameter domain);
// the machined side is the normals' side the passes were planned on. Heights beyond `window` mm are
// reported as NaN (no tool near: outside the finished area).
ScallopCheck check_scallop(const geometry::NurbsSurface& surface, const std::vector<ZoneMachining>& zones, const Tool& tool, double u0, double u1,
                           double v0, double v1, int count_u, int count_v, double window = 0.05);

}  // namespace drom::paths
