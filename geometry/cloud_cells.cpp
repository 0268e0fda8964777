#include "geometry/cloud_cells.hpp"

#include "geometry/cloud_kdtree.hpp"

#include <Eigen/Dense>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

namespace drom::geometry {

double typical_spacing(std::span<const Eigen::Vector3d> points, double* p90) {
  if (points.size() < 9) {
    if (p90) *p90 = 0;
    return 0;
  }
  return typical_spacing(CloudKdTree(points), points, p90);
}

double typical_spacing(const CloudKdTree& tree, std::span<const Eigen::Vector3d> points, double* p90) {
  if (p90) *p90 = 0;
  if (points.size() < 9) return 0;
  std::mt19937 rng(45);
  const std::size_t n = points.size(), m = std::min<std::size_t>(n, 4000);
  std::vector<double> d8;
  std::vector<int> near;
  std::vector<double> d2;
  for (std::size_t k = 0; k < m; ++k) {
    const std::size_t i = n == m ? k : std::uniform_int_distribution<std::size_t>(0, n - 1)(rng);
    tree.nearest(points[i], 9, near, d2);
    if (d2.size() == 9) d8.push_back(std::sqrt(d2.back()));
  }
  if (d8.empty()) return 0;
  std::sort(d8.begin(), d8.end());
  const double scale = 1 / std::sqrt(8 / std::numbers::pi);
  if (p90) *p90 = d8[static_cast<std::size_t>(0.9 * static_cast<double>(d8.size() - 1))] * scale;
  return d8[d8.size() / 2] * scale;
}

CloudCells thin_cloud(std::span<const Eigen::Vector3d> points, double cell, double radius) {
  CloudCells out;
  out.cell = cell;
  if (points.empty()) return out;
  Eigen::Vector3d lo = Eigen::Vector3d::Constant(std::numeric_limits<double>::infinity());
  for (const auto& p : points) lo = lo.cwiseMin(p);
  const auto key = [&](const Eigen::Vector3d& p) {
    const auto i = static_cast<std::uint64_t>((p.x() - lo.x()) / cell), j = static_cast<std::uint64_t>((p.y() - lo.y()) / cell), k = static_cast<std::uint64_t>((p.z() - lo.z()) / cell);
    return (i << 42) | (j << 21) | k;
  };
  std::vector<std::pair<std::uint64_t, int>> order(points.size());
  for (std::size_t i = 0; i < points.size(); ++i) order[i] = {key(points[i]), static_cast<int>(i)};
  tbb::parallel_sort(order.begin(), order.end());
  for (std::size_t i = 0; i < order.size();) {
    std::size_t j = i;
    Eigen::Vector3d sum = Eigen::Vector3d::Zero();
    std::vector<int> members;
    while (j < order.size() && order[j].first == order[i].first) sum += points[static_cast<std::size_t>(order[j].second)], members.push_back(order[j].second), ++j;
    out.centroids.push_back(sum / static_cast<double>(members.size()));
    out.members.push_back(std::move(members));
    i = j;
  }
  const CloudKdTree tree(out.centroids);
  out.neighbours.resize(out.centroids.size());
  tbb::parallel_for(std::size_t(0), out.centroids.size(), [&](std::size_t i) {
    std::vector<int>& near = out.neighbours[i];
    tree.within(out.centroids[i], radius, near);
    near.erase(std::remove(near.begin(), near.end(), static_cast<int>(i)), near.end());
    std::sort(near.begin(), near.end());
  });
  return out;
}

std::vector<Eigen::Vector3d> thinned(std::span<const Eigen::Vector3d> points, double cell) {
  std::vector<std::pair<std::uint64_t, std::size_t>> keys(points.size());
  const auto index = [&](double v) { return static_cast<std::uint64_t>(static_cast<std::int64_t>(std::floor(v / cell)) + (std::int64_t{1} << 20)); };
  for (std::size_t i = 0; i < points.size(); ++i) keys[i] = {(index(points[i].x()) << 42) | (index(points[i].y()) << 21) | index(points[i].z()), i};
  tbb::parallel_sort(keys.begin(), keys.end());
  std::vector<Eigen::Vector3d> out;
  for (std::size_t i = 0; i < keys.size(); ++i)
    if (i == 0 || keys[i].first != keys[i - 1].first) out.push_back(points[keys[i].second]);
  return out;
}

ScanSurvey::ScanSurvey(std::span<const Eigen::Vector3d> points) : tree(points) {
  spacing = typical_spacing(tree, points, &spacing_p90);
  const double cell = std::max(0.2, 1.5 * spacing);
  cells = thin_cloud(points, cell, 2.5 * cell);
}

LocalPlane fit_plane(std::span<const Eigen::Vector3d> points) {
  LocalPlane p;
  if (points.empty()) return p;
  for (const auto& q : points) p.centroid += q;
  p.centroid /= static_cast<double>(points.size());
  Eigen::Matrix3d cov = Eigen::Matrix3d::Zero();
  for (const auto& q : points) cov += (q - p.centroid) * (q - p.centroid).transpose();
  const Eigen::SelfAdjointEigenSolver<Eigen::Matrix3d> eig(cov / static_cast<double>(points.size()));
  p.normal = eig.eigenvectors().col(0), p.v = eig.eigenvectors().col(1), p.u = eig.eigenvectors().col(2);
  p.spread = eig.eigenvalues().cwiseMax(0.0);
  return p;
}

double fit_quadric(std::span<const Eigen::Vector3d> points, const LocalPlane& frame, Eigen::Matrix<double, 6, 1>* coefficients) {
  const int n = static_cast<int>(points.size());
  Eigen::MatrixXd a(n, 6);
  Eigen::VectorXd w(n);
  for (int r = 0; r < n; ++r) {
    const Eigen::Vector3d d = points[static_cast<std::size_t>(r)] - frame.centroid;
    const double u = d.dot(frame.u), v = d.dot(frame.v);
    a.row(r) << 1, u, v, u * u, u * v, v * v;
    w(r) = d.dot(frame.normal);
  }
  const Eigen::VectorXd c = a.colPivHouseholderQr().solve(w);
  if (coefficients) *coefficients = c;
  return std::sqrt((a * c - w).squaredNorm() / std::max(1, n - 6));
}

namespace {

// The variance of a fitted plane's height at x per unit noise variance: 1/n at its centroid, growing
// with the distance from it over the points' spread (ordinary least squares' leverage).
double leverage(const LocalPlane& p, std::size_t n, const Eigen::Vector3d& x) {
  const double count = static_cast<double>(std::max<std::size_t>(n, 1));
  const Eigen::Vector3d d = x - p.centroid;
  const double du = d.dot(p.u), dv = d.dot(p.v);
  return (1 + du * du / std::max(p.spread[2], 1e-12) + dv * dv / std::max(p.spread[1], 1e-12)) / count;
}

struct PlaneFit {
  Eigen::Vector3d centroid = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::UnitZ();
  double sse = 0;
  LocalPlane plane;
  std::size_t count = 0;
};

PlaneFit plane_fit(const std::vector<Eigen::Vector3d>& q) {
  const LocalPlane l = fit_plane(q);
  return {l.centroid, l.normal, l.spread[0] * static_cast<double>(q.size()), l, q.size()};
}

}  // namespace

double TwoPlanes::line_uncertainty(const Eigen::Vector3d& x) const {
  const double k = normal_a.dot(normal_b), sine = std::sqrt(std::max(1e-6, 1 - k * k));
  return residual * std::sqrt(leverage(plane_a, count_a, x) + leverage(plane_b, count_b, x)) / sine;
}

TwoPlanes fit_two_planes(std::span<const Eigen::Vector3d> q, const LocalPlane& frame, double reach, double flat, double smooth, double share) {
  TwoPlanes out;
  if (q.size() < 16) return out;
  double best = std::numeric_limits<double>::infinity();
  PlaneFit a, b;
  // A split of the points into two sides: both fitted, and kept when they leave less than the best so far.
  const auto consider = [&](const std::vector<Eigen::Vector3d>& qa, const std::vector<Eigen::Vector3d>& qb) {
    if (qa.size() < 5 || qb.size() < 5) return false;
    const PlaneFit pa = plane_fit(qa), pb = plane_fit(qb);
    const double rms = std::sqrt((pa.sse + pb.sse) / static_cast<double>(q.size() - 6));
    if (!(rms < best)) return false;
    best = rms, a = pa, b = pb;
    return true;
  };
  for (int d = 0; d < 8; ++d) {
    const double angle = std::numbers::pi * d / 8;
    const Eigen::Vector3d dir = std::cos(angle) * frame.u + std::sin(angle) * frame.v;
    for (const double offset : {-0.5 * reach, -0.25 * reach, 0.0, 0.25 * reach, 0.5 * reach}) {
      std::vector<Eigen::Vector3d> qa, qb;
      for (const auto& p : q) ((p - frame.centroid).dot(dir) < offset ? qa : qb).push_back(p);
      consider(qa, qb);
    }
  }
  // The split refined: each point to the plane it is nearer, both planes fitted again.
  const auto refine = [&] {
    for (int round = 0; round < 4 && std::isfinite(best); ++round) {
      std::vector<Eigen::Vector3d> qa, qb;
      for (const auto& p : q) (std::abs(a.normal.dot(p - a.centroid)) <= std::abs(b.normal.dot(p - b.centroid)) ? qa : qb).push_back(p);
      if (!consider(qa, qb)) break;
    }
  };
  refine();
  // Where no straight line across the points' plane parts the two faces (a wall's top rows and the
  // points of the face above near its edge overlap, seen along the plane of them all), each point's
  // six nearest give a plane, and the points within `flat` of it one side. In a point's neighbourhood
  // (64 points at most: the square of their count is paid), not over a crease search's hundreds.
  if (!(best <= flat) && q.size() <= 64) {
    const double before = best;
    std::vector<std::pair<double, std::size_t>> by_distance(q.size());
    for (std::size_t s = 0; s < q.size(); ++s) {
      for (std::size_t r = 0; r < q.size(); ++r) by_distance[r] = {(q[r] - q[s]).squaredNorm(), r};
      std::partial_sort(by_distance.begin(), by_distance.begin() + 6, by_distance.end());
      std::vector<Eigen::Vector3d> patch;
      for (std::size_t r = 0; r < 6; ++r) patch.push_back(q[by_distance[r].second]);
      const LocalPlane seed = fit_plane(patch);
      std::vector<Eigen::Vector3d> qa, qb;
      for (const auto& p : q) (std::abs(seed.normal.dot(p - seed.centroid)) <= flat ? qa : qb).push_back(p);
      consider(qa, qb);
    }
    if (best < before) refine();
  }
  if (!(best <= flat) || !(best < share * smooth)) return out;
  if (std::abs(a.normal.dot(b.normal)) > std::cos(15 * std::numbers::pi / 180)) return out;  // nearly one plane
  // The planes fitted once more without the points near both (within three residuals): under noise
  // those go to whichever plane they happen to be nearer, each plane gets the other's low points near
  // the line, and the line sinks (by about 0.7 noise deviations on a ridge at 24 degrees).
  {
    std::vector<Eigen::Vector3d> qa, qb;
    for (const auto& p : q) {
      const double da = std::abs(a.normal.dot(p - a.centroid)), db = std::abs(b.normal.dot(p - b.centroid));
      if (std::max(da, db) <= 3 * best) continue;
      (da <= db ? qa : qb).push_back(p);
    }
    if (qa.size() >= 5 && qb.size() >= 5) a = plane_fit(qa), b = plane_fit(qb);
  }
  out.found = true;
  out.normal_a = a.normal, out.point_a = a.centroid, out.normal_b = b.normal, out.point_b = b.centroid;
  out.residual = best;
  out.line_direction = a.normal.cross(b.normal).normalized();
  // The line's point nearest the points' centroid: x = c + alpha n_a + beta n_b on both planes.
  const Eigen::Vector3d c = frame.centroid;
  const double k = a.normal.dot(b.normal);
  Eigen::Matrix2d m;
  m << 1, k, k, 1;
  const Eigen::Vector2d ab = m.partialPivLu().solve(Eigen::Vector2d(a.normal.dot(a.centroid - c), b.normal.dot(b.centroid - c)));
  out.line_point = c + ab.x() * a.normal + ab.y() * b.normal;
  out.plane_a = a.plane, out.plane_b = b.plane, out.count_a = a.count, out.count_b = b.count;
  for (const auto& p : q) {
    const double da = std::abs(a.normal.dot(p - a.centroid)), db = std::abs(b.normal.dot(p - b.centroid));
    if (std::max(da, db) > 3 * best) out.hinge = std::max(out.hinge, da <= db ? leverage(a.plane, a.count, p) : leverage(b.plane, b.count, p));
  }
  return out;
}

namespace {

Eigen::Matrix<double, 6, 1> monomials(const Eigen::Vector2d& g) { return (Eigen::Matrix<double, 6, 1>() << 1, g.x(), g.y(), g.x() * g.x(), g.x() * g.y(), g.y() * g.y()).finished(); }

}  // namespace

LocalSurface::LocalSurface(std::span<const Eigen::Vector3d> q, double flat, int own) {
  if (q.size() < 10) return;
  frame_ = fit_plane(q);
  count_ = q.size();
  normal_.setZero();
  lowest_ = std::numeric_limits<double>::infinity(), highest_ = -lowest_;
  double reach = 0;
  for (const auto& p : q) {
    const Eigen::Vector2d g = uv(p);
    normal_ += monomials(g) * monomials(g).transpose();
    const double w = (p - frame_.centroid).dot(frame_.normal);
    lowest_ = std::min(lowest_, w), highest_ = std::max(highest_, w);
    reach = std::max(reach, g.norm());
  }
  const double smooth = fit_quadric(q, frame_, &quadric_);
  residual_ = smooth;
  if (smooth <= flat) {
    kind_ = Kind::quadric;
    return;
  }
  two_ = fit_two_planes(q, frame_, reach, flat, smooth);
  if (two_.found) {
    line_uv_ = uv(two_.line_point);
    line_dir_ = {two_.line_direction.dot(frame_.u), two_.line_direction.dot(frame_.v)};
    if (line_dir_.norm() > 0.5) {
      line_dir_.normalize();
      const Eigen::Vector2d a = uv(two_.point_a);
      side_a_ = line_dir_.x() * (a.y() - line_uv_.y()) - line_dir_.y() * (a.x() - line_uv_.x()) >= 0 ? 1 : -1;
      kind_ = Kind::crease;
      return;
    }
  }
  // The face: the neighbours within three times `flat` of the plane of the first `own` points; or,
  // where those straddle the crease, the larger side of the split that leaves it flattest.
  const LocalPlane first = fit_plane(q.subspan(0, std::min<std::size_t>(static_cast<std::size_t>(own), q.size())));
  std::vector<Eigen::Vector3d> face;
  for (const auto& p : q)
    if (std::abs(first.normal.dot(p - first.centroid)) <= 3 * flat) face.push_back(p);
  if (face.size() < 10) {
    face.clear();
    for (int d = 0; d < 8; ++d) {
      const double angle = std::numbers::pi * d / 8;
      const Eigen::Vector3d dir = std::cos(angle) * frame_.u + std::sin(angle) * frame_.v;
      for (const double offset : {-0.5, -0.25, 0.0, 0.25, 0.5})
        for (const double sign : {1.0, -1.0}) {
          std::vector<Eigen::Vector3d> side;
          for (const auto& p : q)
            if (sign * ((p - frame_.centroid).dot(dir) - offset * reach) >= 0) side.push_back(p);
          if (side.size() < std::max<std::size_t>(10, face.size() + 1)) continue;
          if (std::sqrt(fit_plane(side).spread[0]) <= flat) face = side;
        }
    }
    if (face.size() < 10) return;
  }
  face_ = fit_plane(face);
  if (fit_quadric(face, face_, &face_quadric_) > flat) return;
  kind_ = Kind::face;
}

Eigen::Vector3d LocalSurface::at(const Eigen::Vector2d& g) const {
  const Eigen::Vector3d base = frame_.centroid + g.x() * frame_.u + g.y() * frame_.v;
  switch (kind_) {
    case Kind::quadric:
      return base + monomials(g).dot(quadric_) * frame_.normal;
    case Kind::crease: {
      // The spot's side of the line, and that side's plane's point over the spot; one that falls past
      // the line is the line's nearest point.
      const auto side_of = [&](const Eigen::Vector2d& h) { return line_dir_.x() * (h.y() - line_uv_.y()) - line_dir_.y() * (h.x() - line_uv_.x()); };
      const bool on_a = (side_of(g) >= 0 ? 1 : -1) == side_a_;
      const Eigen::Vector3d& n = on_a ? two_.normal_a : two_.normal_b;
      const Eigen::Vector3d& o = on_a ? two_.point_a : two_.point_b;
      // Along the frame's normal where the plane faces the frame (within 60°), so the point stays over
      // its spot; else the plane's point nearest the spot.
      const double facing = n.dot(frame_.normal);
      const Eigen::Vector3d p = std::abs(facing) >= 0.5 ? Eigen::Vector3d(base + n.dot(o - base) / facing * frame_.normal) : Eigen::Vector3d(base - n.dot(base - o) * n);
      if (((side_of(uv(p)) >= 0 ? 1 : -1) == side_a_) == on_a) return p;
      return two_.line_point + (p - two_.line_point).dot(two_.line_direction) * two_.line_direction;
    }
    case Kind::face: {
      // The face's quadric along its own normal, above the spot's foot on the face's plane.
      const Eigen::Vector3d d = base - face_.centroid;
      const Eigen::Vector2d f(d.dot(face_.u), d.dot(face_.v));
      return face_.centroid + f.x() * face_.u + f.y() * face_.v + monomials(f).dot(face_quadric_) * face_.normal;
    }
    case Kind::none:
      break;
  }
  return Eigen::Vector3d::Constant(std::numeric_limits<double>::quiet_NaN());
}

double LocalSurface::leverage(const Eigen::Vector2d& g) const {
  const Eigen::Matrix<double, 6, 1> x = monomials(g);
  return x.dot(normal_.ldlt().solve(x));
}

std::optional<LocalSurface::Spot> LocalSurface::spot(const Eigen::Vector2d& g) const {
  if (kind_ == Kind::quadric) {
    const Eigen::Vector3d on = at(g);
    if (!std::isfinite(on.x())) return std::nullopt;
    return Spot{on, frame_.normal, leverage(g), residual_};
  }
  if (kind_ != Kind::crease) return std::nullopt;
  const Eigen::Vector3d on = at(g);
  if (!std::isfinite(on.x())) return std::nullopt;
  // The side whose plane holds `on`; a point on the line (the spot fell past it) belongs to neither.
  const double da = std::abs(two_.normal_a.dot(on - two_.point_a)), db = std::abs(two_.normal_b.dot(on - two_.point_b));
  const bool on_a = da <= db;
  const Eigen::Vector3d off_line = (on - two_.line_point) - (on - two_.line_point).dot(two_.line_direction) * two_.line_direction;
  if (off_line.norm() < 1e-9) return std::nullopt;
  return on_a ? Spot{on, two_.normal_a, geometry::leverage(two_.plane_a, two_.count_a, on), two_.residual}
              : Spot{on, two_.normal_b, geometry::leverage(two_.plane_b, two_.count_b, on), two_.residual};
}

LocalSurface::Spot LocalSurface::plane_spot(const Eigen::Vector2d& g) const {
  const Eigen::Vector3d on = frame_.centroid + g.x() * frame_.u + g.y() * frame_.v;
  return Spot{on, frame_.normal, geometry::leverage(frame_, count_, on), std::sqrt(std::max(0.0, frame_.spread[0]))};
}

double safe_lift_deviations(std::size_t fits) {
  // The one-sided tail 0.5 erfc(z / sqrt 2) = 1 / (10 fits), by bisection (erfc falls monotonically).
  const double tail = 1 / (10.0 * static_cast<double>(std::max<std::size_t>(fits, 1)));
  double lo = 0, hi = 40;
  for (int it = 0; it < 100; ++it) {
    const double mid = 0.5 * (lo + hi);
    (0.5 * std::erfc(mid / std::numbers::sqrt2) > tail ? lo : hi) = mid;
  }
  return std::max(3.0, 0.5 * (lo + hi));
}

}  // namespace drom::geometry
