#pragma once
// The visibility matrix of a cloud (Makki 2009 §3-3, Algorithms 2-3, §3.3.3): which fixed tool
// orientations can machine each point. Rows are the points with a normal, columns the directions of
// a (phi, theta) grid of the unit sphere; a bit is set when the direction passes three tests:
//   1. tool visibility: it lies in the hollow cone v1 <= angle(d, n) <= v2 around the point's normal
//      (no cutting at the ball's tip, where the cutting speed is zero, nor with its flank);
//   2. global visibility: the tool set on the point along d (its cutter touching the point with the
//      point's normal) has nothing of the cloud, the stock or the fixture inside its body above the
//      cutter, its shank, or its holder (the cutter itself is the drop's business, as in the seed);
//   3. machine visibility: the machine can orient its tool along d within its rotary strokes (and,
//      optionally, reach the cloud's bounding box within its linear strokes), through machine/'s
//      inverse kinematics. The seed runs it first, and so does this: unreachable columns stay empty.
// Columns are bitsets, so grouping counts coverage and overlap with popcounts (paths/copy/packets.hpp).
#include "machine/kinematics.hpp"
#include "paths/cutter/tool_assembly.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

namespace drom::paths {

// The (phi, theta) grid: theta from +Z in [0, 180) by `theta_step`, phi in [0, 360) by `phi_step`
// (degrees): (360 / phi_step) x (180 / theta_step) directions, the seed's counts (648 at 10/10, 216
// at 10/30). The pole's copies (theta = 0 for every phi) are kept once.
struct Directions {
  std::vector<Eigen::Vector3d> unit;
  std::vector<double> phi, theta;  // degrees
  int grid_count = 0;              // before the pole's copies were merged
};
Directions direction_grid(double phi_step, double theta_step);

// A solid the tool must not enter: an axis-aligned box, or a cylinder along Z (part frame, mm).
struct Obstacle {
  std::string name = "fixture";
  enum class Kind { box, cylinder } kind = Kind::box;
  Eigen::Vector3d lo = Eigen::Vector3d::Zero(), hi = Eigen::Vector3d::Zero();  // box corners; cylinder: lo = base centre, hi.z() = top, hi.x() = radius
  bool bottom = true;  // the box's bottom face sampled too (the stock's base stands on the table: it is not)
};
// The obstacle's surface sampled at `spacing` mm: the points the tests and the drop see.
std::vector<Eigen::Vector3d> obstacle_surface(const Obstacle& obstacle, double spacing);

struct VisibilitySettings {
  double phi_step = 10, theta_step = 10;  // degrees
  double cone_min = 10, cone_max = 80;    // v1, v2 (degrees)
  ToolAssembly tool;
  // A point closer to the tool's body than this (mm) is a graze, not a collision: the noise of the
  // scan and of the normals (a perfect part's neighbours touch the body exactly).
  double graze = 0.05;
  const machine::Kinematics* machine = nullptr;  // null: every direction reachable
  bool check_travel = true;                      // the cloud's bounding box within the linear strokes
};

struct VisibilityMatrix {
  Directions directions;
  int points = 0;
  std::vector<std::vector<std::uint64_t>> columns;  // per direction: bit i set when point i is visible
  std::vector<char> reachable;                      // per direction: within the machine's strokes
  std::vector<Eigen::Vector2d> rotary;              // per direction: the machine's two rotary angles (deg) on the branch kept
  long long tool_visible = 0;                       // bits the cone set
  long long collisions = 0;                         // of those, cleared by a body collision
  bool test(int point, int direction) const {
    return (columns[static_cast<std::size_t>(direction)][static_cast<std::size_t>(point) >> 6] >> (point & 63)) & 1u;
  }
  int column_count(int direction) const;
};

// Which directions the machine reaches (with rotary angles), for a cloud's bounding box.
struct Reach {
  bool ok = true;
  Eigen::Vector2d rotary = Eigen::Vector2d::Zero();  // degrees
  std::string why;  // when not: "A = 131.2 deg beyond its stroke [-30, 120] deg"
};
Reach machine_reach(const machine::Kinematics& machine, const Eigen::Vector3d& direction, const Eigen::Vector3d& box_lo, const Eigen::Vector3d& box_hi,
                    bool check_travel);

// The tool's body along one direction against a collision cloud: built once per direction.
class BodyCheck {
 public:
  // `collision`: the whole cloud and the obstacles' surfaces (part frame).
  BodyCheck(std::span<const Eigen::Vector3d> collision, const Eigen::Vector3d& direction, const ToolAssembly& tool, double graze);
  ~BodyCheck();
  BodyCheck(BodyCheck&&) noexcept;
  // Whether the tool, its cutter touching point p with (outward) normal n, has its body clear.
  bool clear(const Eigen::Vector3d& p, const Eigen::Vector3d& n) const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

// `collision`: every point the tool must not touch (the cloud, the obstacles' surfaces); `points` and
// `normals`: the rows (the points with a normal, part frame).
VisibilityMatrix visibility_matrix(std::span<const Eigen::Vector3d> collision, std::span<const Eigen::Vector3d> points, std::span<const Eigen::Vector3d> normals,
                                   const VisibilitySettings& settings);

}  // namespace drom::paths
