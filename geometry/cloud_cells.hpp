#pragma once
// A scan thinned to one centroid per cubic cell, each knowing its points and its neighbouring
// centroids: the scale at which the shape of a scan's surface (its rim, its creases) is read, above
// its spacing and its noise. Shared by cloud_rim.hpp and cloud_creases.hpp.
#include "geometry/cloud_kdtree.hpp"

#include <Eigen/Core>

#include <optional>
#include <span>
#include <vector>

namespace drom::geometry {

// The scan's typical spacing: the median distance to the 8th neighbour of up to 4 000 points drawn
// with a fixed seed, over sqrt(8 / pi) (on a surface sampled at density 1/s^2, a disc of radius d
// holds pi d^2 / s^2 points); `p90`, when given, receives the 90th percentile the same way.
double typical_spacing(std::span<const Eigen::Vector3d> points, double* p90 = nullptr);
double typical_spacing(const CloudKdTree& tree, std::span<const Eigen::Vector3d> points, double* p90 = nullptr);

struct CloudCells {
  double cell = 0;
  std::vector<Eigen::Vector3d> centroids;
  std::vector<std::vector<int>> members;     // per cell: its points (indices into the scan)
  std::vector<std::vector<int>> neighbours;  // per cell: the other cells whose centroid lies within `radius`
};

CloudCells thin_cloud(std::span<const Eigen::Vector3d> points, double cell, double radius);

// What a scan's analyses (its noise, rim, creases and holes) share, made once: a k-d tree of its
// points, its typical spacing and 90th percentile, and its cells (1.5 spacings, at least 0.2 mm;
// neighbours within 2.5 cells).
struct ScanSurvey {
  explicit ScanSurvey(std::span<const Eigen::Vector3d> points);
  CloudKdTree tree;
  double spacing = 0, spacing_p90 = 0;
  CloudCells cells;
};

// One point per cube of `cell` mm (the first, in order): a cloud thinned for tests that need its
// shape, not its every point.
std::vector<Eigen::Vector3d> thinned(std::span<const Eigen::Vector3d> points, double cell);

// The least-squares plane of some points: their centroid, and the unit normal (least spread) with
// the two directions in the plane (most spread first) and the three spreads (eigenvalues, least first).
struct LocalPlane {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::UnitZ(), u = Eigen::Vector3d::UnitX(), v = Eigen::Vector3d::UnitY();
  Eigen::Vector3d spread = Eigen::Vector3d::Zero();
};
LocalPlane fit_plane(std::span<const Eigen::Vector3d> points);

// The residual (standard deviation, mm) of the quadric w = a + b u + c v + d u^2 + e uv + f v^2
// fitted in `frame`, and its coefficients: what a smooth surface leaves.
double fit_quadric(std::span<const Eigen::Vector3d> points, const LocalPlane& frame, Eigen::Matrix<double, 6, 1>* coefficients = nullptr);

// What a flat face of a scan with this noise (standard deviation, mm) may leave about its plane: three
// deviations and 5 µm. The threshold the rim, the holes and the creases read a scan's shape by.
inline double flat_face_residual(double noise) { return 3 * noise + 0.005; }

// How many standard deviations above its fit a point put where the scan has none is lifted, so that
// among `fits` independent local fits the lowest stays above the surface with odds of about 10 to 1:
// the normal quantile at 1 - 1 / (10 fits), and never under 3 (2 000 fits: 3.9; 60 000: 4.6). Three
// deviations flat, where a sparse scan is filled from a couple of thousand neighbourhoods, left a
// few fits 3 deviations low, and the tool 0.05 mm into the true surface.
double safe_lift_deviations(std::size_t fits);

// Two planes meeting on a line: a sharp crease. Found by splitting the points along eight directions
// in their plane at five offsets (the split that leaves the least residual), then each point given to
// the plane it is nearer and both refitted; where that leaves more than `flat` among 64 points or
// fewer, split again by the plane of each point's six nearest (the points within `flat` of it one
// side) and refined the same way. Found when both are flat to `flat` (residual standard
// deviation, mm), flatter than `share` of the quadric's residual `smooth` (half by default), and 15°
// or more apart; then each refitted without the points near both, which noise would give to either.
struct TwoPlanes {
  bool found = false;
  Eigen::Vector3d normal_a = Eigen::Vector3d::UnitZ(), point_a = Eigen::Vector3d::Zero();
  Eigen::Vector3d normal_b = Eigen::Vector3d::UnitZ(), point_b = Eigen::Vector3d::Zero();
  Eigen::Vector3d line_point = Eigen::Vector3d::Zero(), line_direction = Eigen::Vector3d::UnitX();  // where they meet
  double residual = 0;
  LocalPlane plane_a, plane_b;  // the final fits, and the points each took
  std::size_t count_a = 0, count_b = 0;
  // The largest leverage of a point in either plane's fit: near 1 where a plane hangs on one point
  // (a row of points and one beside it, fitted exactly whatever lies between).
  double hinge = 0;
  // mm: one standard deviation of the line's position at x (on it) from the noise: each plane's height
  // there (its offset and its tilt, by least squares' leverage) over the sine of the planes' angle.
  double line_uncertainty(const Eigen::Vector3d& x) const;
};
TwoPlanes fit_two_planes(std::span<const Eigen::Vector3d> points, const LocalPlane& frame, double reach, double flat, double smooth, double share = 0.5);

// The surface a neighbourhood of scanned points describes, for putting points where the scan has
// none: a quadric over their plane; where a sharp crease runs through them, two planes, each on its
// side of their line; where a crease lies at the neighbourhood's edge (a few points across, too few
// for two planes), the quadric of the face of its `own` first points (the nearest to where it was
// taken). `flat`: what a smooth face may leave (flat_face_residual).
class LocalSurface {
 public:
  enum class Kind { quadric, crease, face, none };
  LocalSurface(std::span<const Eigen::Vector3d> neighbourhood, double flat, int own = 8);
  Kind kind() const { return kind_; }
  const LocalPlane& frame() const { return frame_; }
  const TwoPlanes& crease() const { return two_; }
  Eigen::Vector2d uv(const Eigen::Vector3d& p) const { return {(p - frame_.centroid).dot(frame_.u), (p - frame_.centroid).dot(frame_.v)}; }
  // The surface point above the spot (u, v) of the neighbourhood's plane (at a crease, on the spot's
  // side's plane: over the spot, or its nearest point where that plane stands more than 60° steep in
  // the frame); NaN where this neighbourhood cannot tell (no model).
  Eigen::Vector3d at(const Eigen::Vector2d& uv) const;
  // The fit's variance there over the noise's: x^T (A^T A)^-1 x for the quadric's design over the
  // neighbourhood (about 6 / n amid the points, more towards their edge, above 1 beyond them).
  double leverage(const Eigen::Vector2d& uv) const;
  // What the quadric leaves over the neighbourhood (residual standard deviation, mm).
  double residual() const { return residual_; }
  // The model over a spot, for standing a floor on it: the surface point, the normal its height is
  // measured along, that height's variance over the noise's (the quadric's leverage; at a crease, the
  // spot's side's plane's) and what the model leaves of its points (mm). None where the model was not
  // fitted over the spot: no model, a face's few points, or a crease's spot past its side's line.
  struct Spot {
    Eigen::Vector3d on, normal;
    double leverage = 0, residual = 0;
  };
  std::optional<Spot> spot(const Eigen::Vector2d& uv) const;
  // The neighbourhood's least-squares plane over the spot, the same way (its leverage by ordinary least
  // squares over the neighbourhood's points, its residual theirs about it).
  Spot plane_spot(const Eigen::Vector2d& uv) const;
  // How far the neighbourhood's points stand off its plane, lowest and highest.
  double lowest() const { return lowest_; }
  double highest() const { return highest_; }

 private:
  Kind kind_ = Kind::none;
  LocalPlane frame_, face_;
  Eigen::Matrix<double, 6, 1> quadric_ = Eigen::Matrix<double, 6, 1>::Zero(), face_quadric_ = Eigen::Matrix<double, 6, 1>::Zero();
  Eigen::Matrix<double, 6, 6> normal_ = Eigen::Matrix<double, 6, 6>::Identity();
  TwoPlanes two_;
  Eigen::Vector2d line_uv_ = Eigen::Vector2d::Zero(), line_dir_ = Eigen::Vector2d::UnitX();
  double side_a_ = 1, lowest_ = 0, highest_ = 0, residual_ = 0;
  std::size_t count_ = 0;
};

}  // namespace drom::geometry
