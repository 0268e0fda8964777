#pragma once
// A tensor-product rational B-spline patch (NURBS). Bézier patches (one span, clamped knots) and
// non-rational B-splines (all weights 1) are the same type, built by their own factories. Evaluation
// gives the point and its first and second parametric derivatives (Piegl & Tiller, The NURBS Book,
// A2.3 and A4.4): the hot path of path planning, so it allocates nothing.
#include <Eigen/Core>

#include <vector>

namespace drom::geometry {

// S and its partial derivatives at (u, v).
struct SurfaceDerivatives {
  Eigen::Vector3d point, du, dv, duu, duv, dvv;
};

class NurbsSurface {
 public:
  static constexpr int kMaxDegree = 25;  // OpenCASCADE's limit too

  // The flat unit square z = 0 (bilinear), so holders of a surface can be default-constructed.
  NurbsSurface();

  // Control point (i, j), i along u and j along v, is points[i * count_v + j]. Knot vectors are
  // clamped or not, of size count + degree + 1, non-decreasing, with a non-empty domain. Weights are
  // positive; empty means all 1 (a non-rational B-spline). Throws std::invalid_argument, saying what
  // is wrong, on any inconsistency.
  NurbsSurface(int degree_u, int degree_v, std::vector<double> knots_u, std::vector<double> knots_v, int count_u, int count_v,
               std::vector<Eigen::Vector3d> points, std::vector<double> weights = {});

  // A Bézier patch of count_u x count_v control points (degrees count - 1), on [0, 1]^2.
  static NurbsSurface bezier(int count_u, int count_v, std::vector<Eigen::Vector3d> points, std::vector<double> weights = {});
  // Clamped uniform knots on [0, 1] for count control points of the given degree.
  static std::vector<double> clamped_uniform_knots(int degree, int count);

  Eigen::Vector3d point(double u, double v) const;
  SurfaceDerivatives derivatives(double u, double v) const;

  // The same surface with its domain mapped affinely onto [0, 1]^2 (knots rescaled).
  NurbsSurface with_unit_domain() const;

  int degree_u() const { return degree_u_; }
  int degree_v() const { return degree_v_; }
  int count_u() const { return count_u_; }
  int count_v() const { return count_v_; }
  const std::vector<double>& knots_u() const { return knots_u_; }
  const std::vector<double>& knots_v() const { return knots_v_; }
  const std::vector<Eigen::Vector3d>& points() const { return points_; }
  const std::vector<double>& weights() const { return weights_; }
  bool is_rational() const { return rational_; }
  double u_min() const { return knots_u_[degree_u_]; }
  double u_max() const { return knots_u_[count_u_]; }
  double v_min() const { return knots_v_[degree_v_]; }
  double v_max() const { return knots_v_[count_v_]; }

 private:
  int degree_u_, degree_v_, count_u_, count_v_;
  std::vector<double> knots_u_, knots_v_;
  std::vector<Eigen::Vector3d> points_;
  std::vector<double> weights_;
  bool rational_ = false;
};

}  // namespace drom::geometry
