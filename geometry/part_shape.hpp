#pragma once
// The stock's shape in parametric coordinates p = (u, v, t): u along the part's first direction
// (arc length on the outer surface for a panel), v along the second, t through the thickness from
// the bottom (inner) face. Residual-stress profiles, clamps and pockets are all stated in p.
#include <Eigen/Core>

namespace drom::geometry {

class PartShape {
 public:
  enum class Kind { Plate, Panel, Block };

  // Flat plate [0, lx] x [0, ly] x [0, thickness].
  static PartShape plate(double lx, double ly, double thickness);
  // Cylindrical panel, axis along y, convex up: `lx` is the arc length of the outer surface, the
  // inner surface touches z = 0 at u = lx / 2 and the outer radius is `outer_radius`.
  static PartShape panel(double lx, double ly, double thickness, double outer_radius);
  // Any other part: its bounding box, with the thickness along z (used for STL parts).
  static PartShape block(const Eigen::Vector3d& min_corner, const Eigen::Vector3d& max_corner);

  Kind kind() const { return kind_; }
  double length_u() const { return lu_; }
  double length_v() const { return lv_; }
  double thickness() const { return thickness_; }
  double outer_radius() const { return outer_radius_; }

  Eigen::Vector3d to_parametric(const Eigen::Vector3d& x) const;
  Eigen::Vector3d from_parametric(const Eigen::Vector3d& p) const;
  // Reduced thickness coordinate s in [-1, 1] (docs/design.md §1).
  double reduced_thickness(const Eigen::Vector3d& x) const;
  // Columns: e1 (along u), e2 (along v), e3 (outward thickness normal) at x.
  Eigen::Matrix3d local_frame(const Eigen::Vector3d& x) const;
  // Signed distance to the stock (negative inside); exact for plates and blocks away from edges and
  // corners, and for panels through the thickness and at the end faces. Exact at the surface.
  double signed_distance(const Eigen::Vector3d& x) const;

 private:
  Kind kind_ = Kind::Plate;
  double lu_ = 0, lv_ = 0, thickness_ = 0, outer_radius_ = 0;
  Eigen::Vector3d origin_ = Eigen::Vector3d::Zero();
};

}  // namespace drom::geometry
