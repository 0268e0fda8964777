#pragma once
// A check of drom copy's posted packets that shares no code with the planner (issue 45): it reads the
// CL files drom wrote (its own CSV reader), rebuilds the tool as a solid of revolution of its own
// (cutter, shank, holder), sweeps it along every posted move in each packet's frame, and measures
//   - how deep the swept tool goes into the scan's points and into the true surface (every face of
//     the analytic solid, the hidden sides and the stock's base included): Euclidean depth, mm;
//   - which true points a packet's finishing reaches (the residual between the surface and the swept
//     cutter, capsule distance for a ball), the scallop left where it passes, and the coverage of the
//     true points that any direction the machine reaches could finish (its own visibility: a ball
//     touching the point, the assembly clear of the solid and the base).
// Nothing is taken from the planner but the files it wrote.
#include <Eigen/Core>

#include <filesystem>
#include <limits>
#include <string>
#include <vector>

namespace drom::tests::checker {

struct ToolSpec {
  enum class Kind { ball, torus, flat } kind = Kind::ball;
  double radius = 3;          // R
  double corner = 3;          // r (ball: R, flat: 0)
  double flute_length = 0;    // 0: 2 R
  double shank_radius = 0;    // 0: R
  double gauge_length = 0;    // tip to the holder's face; 0: no holder
  double holder_radius = 0;   // the holder, a cylinder up without end
};

// One CL file: tips in the part frame, one axis for the whole file (3+2), rapids marked.
struct ClFile {
  std::string origin;
  std::vector<Eigen::Vector3d> tips;
  std::vector<char> rapid;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
};
// The columns x, y, z, i, j, k, feed (feed 0: a rapid); throws std::runtime_error naming the line.
ClFile read_cl_csv(const std::filesystem::path& file);

// The tool's section in the (rho, h) half-plane (rho from the axis, h above the tip).
class ToolSolid {
 public:
  explicit ToolSolid(const ToolSpec& spec);
  // > 0 inside the assembly: the distance to its boundary; <= 0 outside (not a distance then).
  double depth(double rho, double h) const;
  bool deeper_than(double rho, double h, double d) const;  // inside, farther than d from the boundary
  // >= 0: the distance from outside to the cutting part (up to the flutes); < 0 inside it.
  double cutter_distance(double rho, double h) const;
  double reach() const;       // widest radius
  double lowest(double rho) const;  // the assembly's lowest height at radius rho (+inf beyond reach)
  const ToolSpec& spec() const { return s_; }

 private:
  ToolSpec s_;
  double flutes_, shank_, gauge_;
  bool inside(double rho, double h) const;
  double boundary_distance(double rho, double h, bool cutter_only) const;
};

struct PathResult {
  std::string origin;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  long long positions = 0;                 // moves (each from the previous position)
  long long over_cloud = 0, over_truth = 0, over_edge = 0;  // moves that take the tool deeper than the tolerance
  double deepest_cloud = 0, deepest_truth = 0, deepest_at_edge = 0;  // mm (0 when nothing is inside)
  Eigen::Vector3d worst_edge_part = Eigen::Vector3d::Zero();
  Eigen::Vector3d worst_cloud_part = Eigen::Vector3d::Zero(), worst_cloud_frame = Eigen::Vector3d::Zero();  // the point reached deepest
  Eigen::Vector3d worst_truth_part = Eigen::Vector3d::Zero(), worst_truth_frame = Eigen::Vector3d::Zero();
  std::string first_over;  // the first move over, described (line of the CL file, kind, depth)
};

// How deep the tool swept along `cl` goes into `cloud` and `truth` (part frame): a move is over when
// some point stands deeper than `tolerance` inside it (cuts and links) or inside it at all (rapids;
// a rapid leaving a cut is judged once it has moved `tolerance` away from the cut's end).
// True points within `edge_radius` of an `edge` point (where a scan ends and the part's edge lies
// somewhere in the next gap) are judged apart: `deepest_at_edge`, moves over `edge_tolerance`.
PathResult check_path(const ClFile& cl, const ToolSpec& tool, const std::vector<Eigen::Vector3d>& cloud, const std::vector<Eigen::Vector3d>& truth, double tolerance,
                      const std::vector<Eigen::Vector3d>& edge = {}, double edge_radius = 0, double edge_tolerance = 0);

struct CoverageSettings {
  ToolSpec tool;              // the finishing tool (a ball here)
  double window = 85;         // degrees: the largest angle between the tool axis and a point's normal
  double max_tilt = 120;      // degrees from +Z the machine's rotary axes reach
  double graze = 0.05;        // mm: nearer the body than this is a graze, not a collision
  double reached = 0.1;       // mm: a point the swept cutter passes within this is finished
  int samples = 2000;         // true points judged (at random, fixed seed)
  // True points within `unsure_radius` of one of these are not judged: where a scan cannot tell the
  // part's edge to better than its spacing (the faces hidden below an open sheet's rim).
  std::vector<Eigen::Vector3d> unsure;
  double unsure_radius = 0;
};

struct CoverageResult {
  long long sampled = 0, machinable = 0, reached = 0;
  double coverage = 1;        // reached / machinable
  double scallop = 0;         // mm: the largest residual over the reached points
  double scallop_p99 = 0;     // its 99th percentile
  std::vector<Eigen::Vector3d> missed;  // machinable points not reached (part frame)
};

// `scanned`, `normals`: the true faces the scan shows (the points to finish); `solid`: every true
// point (hidden faces and base included) the tool must not enter. `finishing`: the packets' CL files.
CoverageResult check_coverage(const std::vector<ClFile>& finishing, const std::vector<Eigen::Vector3d>& scanned, const std::vector<Eigen::Vector3d>& normals,
                              const std::vector<Eigen::Vector3d>& solid, const CoverageSettings& settings);

// The smallest number of directions (from its own grid) that reach `share` of the machinable sampled
// points, up to 3 (4 when none of 3 do): the checker's own answer to "how few packets can do it".
int fewest_directions(const std::vector<Eigen::Vector3d>& scanned, const std::vector<Eigen::Vector3d>& normals, const std::vector<Eigen::Vector3d>& solid,
                      const CoverageSettings& settings, double share);

// The stock's base as points (its top face over [lo, hi] in XY at z = top, and its sides down to
// `bottom`), every `step` mm: the checker's base is points like the rest of the solid.
std::vector<Eigen::Vector3d> base_points(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, double top, double bottom, double step);

}  // namespace drom::tests::checker
