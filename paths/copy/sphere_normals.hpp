#pragma once
// Normals by sphere launching (Makki 2009 §3-2.2, Algorithm 1, with its inverted test set right): for
// each launch direction d, the cloud is turned so that d is +Z, a grid of nodes is laid over it, and
// a sphere of diameter D is dropped at each node (tool_drop.hpp's ball). Where it lands, its contact
// point gets the normal from the contact to the sphere's centre: outward by construction (the sphere
// comes from outside the material), with no scan direction and no propagation. A point touched by
// several launches gets their mean (the normalised sum). Only contact points get a normal: the method
// also thins the cloud (about 10 % of the points in the seed).
//
// Beyond the seed: a sphere whose axis does not pass through the cloud (no point within the grid step
// of its node) is not counted. Dropped beside the cloud's border it would rest on the border point
// from the side and give it a normal tilted by up to 90° (the seed's "limits at the cloud's border").
#include <Eigen/Core>

#include <span>
#include <vector>

namespace drom::paths {

struct SphereLaunchSettings {
  double diameter = 10;  // D, mm (the seed: 10 on the sphere and the mask, 7 on the hip)
  double grid_step = 1;  // Pt = Pl, mm
  std::vector<Eigen::Vector3d> directions = {Eigen::Vector3d::UnitZ()};
  bool inside_only = true;  // count a sphere only where its axis passes through the cloud
};

struct PointNormals {
  std::vector<int> points;               // cloud indices of the points with a normal, increasing
  std::vector<Eigen::Vector3d> normals;  // unit, outward
  std::vector<int> hits;                 // launches that touched each of them
  long long launches = 0;                // spheres dropped
  long long contacts = 0;                // spheres that landed on the cloud and were counted
};

// `blockers`: points a sphere may land on that get no normal (the part's side below a scan's rim:
// a sphere launched from beside the part lands on it, not on the rim's points from the side).
// Throws std::invalid_argument on a non-positive diameter or grid step, or no direction.
PointNormals launch_spheres(std::span<const Eigen::Vector3d> cloud, const SphereLaunchSettings& settings, std::span<const Eigen::Vector3d> blockers = {});

// The angle (rad) between two unit vectors.
double angle_between(const Eigen::Vector3d& a, const Eigen::Vector3d& b);

}  // namespace drom::paths
