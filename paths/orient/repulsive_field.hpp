#pragma once
// The repulsive field of Lacharnay 2014 (seed 000): check surfaces meshed into point obstacles, each
// emitting a Khatib potential U = ½ η (1/r − 1/r0)² within r0 (eq. 2.19), whose force on a tool point is
// F = η (1/r − 1/r0) / r² · (P − O)/r (eq. 2.23); the forces a tool point receives aggregated as F1
// (their sum, eq. 3.15), F2 (the sum over the active count, 3.16) or F3 (the largest force's magnitude
// along the sum, 3.17). Units: mm, N; η in N·mm³ (the seed's 1e-7 N·m³ is 100 N·mm³).
//
// The obstacle points are binned in a uniform grid of cell r0, so a query visits the 27 cells around
// the tool point rather than every obstacle (the seed's MATLAB summed them all: its cost P·N·C_S).
#include "geometry/nurbs_surface.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <filesystem>
#include <array>
#include <cmath>
#include <vector>

namespace drom::paths {

enum class Aggregation { F1, F2, F3 };
const char* aggregation_name(Aggregation a);

struct KhatibParameters {
  double eta = 100;            // N·mm³ (seed Table 3.1: 1e-7 N·m³)
  double influence_radius = 10;  // r0, mm
};

// The force one obstacle O exerts on a tool point P (zero beyond r0; r = 0 is not a point of the
// field and returns zero: a node on an obstacle is a collision the clearance check reports).
Eigen::Vector3d khatib_force(const Eigen::Vector3d& p, const Eigen::Vector3d& o, const KhatibParameters& k);
double khatib_potential(double r, const KhatibParameters& k);

// A triangle soup (a check surface from STL, or a patch triangulated), with one outward material
// normal per triangle (the side the tool must stay on).
struct TriangleSoup {
  std::vector<Eigen::Vector3d> vertices;
  std::vector<std::array<int, 3>> triangles;
  void append(const TriangleSoup& other);
};

// A patch triangulated on a grid at about `step` mm, its triangles oriented like the patch normal
// (flipped when `flip`, so the normal points out of the material towards the tool).
TriangleSoup triangulate_patch(const geometry::NurbsSurface& surface, double step, bool flip);

// Point obstacles with their outward material normals, and the grid that finds them.
class ObstacleCloud {
 public:
  ObstacleCloud() = default;
  ObstacleCloud(std::vector<Eigen::Vector3d> points, std::vector<Eigen::Vector3d> normals, double cell);

  // A patch sampled at iso-parametric nodes about `spacing` apart (the seed's structured mesh).
  static ObstacleCloud from_patch(const geometry::NurbsSurface& surface, double spacing, bool flip_normal, double cell);
  // Triangles sampled on a barycentric grid of about `spacing`: vertices, edges and faces alike.
  static ObstacleCloud from_triangles(const TriangleSoup& soup, double spacing, double cell);
  void append(const ObstacleCloud& other);

  std::size_t size() const { return points_.size(); }
  const std::vector<Eigen::Vector3d>& points() const { return points_; }
  const std::vector<Eigen::Vector3d>& normals() const { return normals_; }
  double cell() const { return cell_; }

  // Calls visit(index) for each obstacle in the cells that may hold points within the cell size of p.
  template <class Visit>
  void for_each_near(const Eigen::Vector3d& p, Visit&& visit) const {
    if (points_.empty()) return;
    const Eigen::Vector3d q = (p - origin_) / cell_;
    const int cx = static_cast<int>(std::floor(q.x())), cy = static_cast<int>(std::floor(q.y())), cz = static_cast<int>(std::floor(q.z()));
    for (int x = std::max(cx - 1, 0); x <= std::min(cx + 1, dims_[0] - 1); ++x)
      for (int y = std::max(cy - 1, 0); y <= std::min(cy + 1, dims_[1] - 1); ++y)
        for (int z = std::max(cz - 1, 0); z <= std::min(cz + 1, dims_[2] - 1); ++z) {
          const std::size_t c = (static_cast<std::size_t>(x) * dims_[1] + y) * dims_[2] + z;
          for (int k = start_[c]; k < start_[c + 1]; ++k) visit(order_[k]);
        }
  }
  // Calls visit(index) for each obstacle in the cells that overlap the ball of `radius` around p (any
  // radius: the cells visited grow with it).
  template <class Visit>
  void for_each_within(const Eigen::Vector3d& p, double radius, Visit&& visit) const {
    if (points_.empty()) return;
    const Eigen::Vector3d lo = (p - origin_).array() / cell_ - radius / cell_, hi = (p - origin_).array() / cell_ + radius / cell_;
    int a[3], b[3];
    for (int d = 0; d < 3; ++d) {
      a[d] = std::max(static_cast<int>(std::floor(lo(d))), 0);
      b[d] = std::min(static_cast<int>(std::floor(hi(d))), dims_[d] - 1);
    }
    for (int x = a[0]; x <= b[0]; ++x)
      for (int y = a[1]; y <= b[1]; ++y)
        for (int z = a[2]; z <= b[2]; ++z) {
          const std::size_t c = (static_cast<std::size_t>(x) * dims_[1] + y) * dims_[2] + z;
          for (int k = start_[c]; k < start_[c + 1]; ++k) visit(order_[k]);
        }
  }
  // The nearest obstacle within `radius` (≤ cell), or -1.
  int nearest(const Eigen::Vector3d& p, double radius) const;

 private:
  // Points binned in a dense grid of cells over their bounding box (compressed rows: start_, order_).
  void rebin();
  std::vector<Eigen::Vector3d> points_, normals_;
  double cell_ = 10;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
  std::array<int, 3> dims_{0, 0, 0};
  std::vector<int> start_, order_;
};

// The aggregated force at P from every obstacle within r0, and how many were active.
struct FieldSample {
  Eigen::Vector3d force = Eigen::Vector3d::Zero();
  int active = 0;
  double nearest = 1e300;  // distance to the nearest obstacle looked at (mm)
};
FieldSample repulsive_force(const ObstacleCloud& obstacles, const Eigen::Vector3d& p, const KhatibParameters& k, Aggregation a);

// Reads the triangles of an ASCII or binary STL (no closedness required: a check surface may be open).
TriangleSoup read_stl_triangles(const std::filesystem::path& path);

}  // namespace drom::paths
