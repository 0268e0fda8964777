#include "reduce/cut_time.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace drom::reduce {

namespace {

// Program time at which segment i first covers `point`, or +inf.
double segment_cover_time(const Eigen::MatrixXd& path, Eigen::Index i, const Eigen::Vector3d& point, double radius, double z_tolerance) {
  if (std::min(path(i, 2), path(i + 1, 2)) > point.z() + z_tolerance) return std::numeric_limits<double>::infinity();  // the tip is not down there
  const Eigen::Vector2d a = path.row(i).head<2>().transpose(), b = path.row(i + 1).head<2>().transpose(), p = point.head<2>();
  const Eigen::Vector2d d = b - a, f = a - p;
  const double A = d.squaredNorm(), B = 2 * f.dot(d), C = f.squaredNorm() - radius * radius;
  double lambda;
  if (C <= 0) lambda = 0;
  else if (A == 0) return std::numeric_limits<double>::infinity();
  else {
    const double disc = B * B - 4 * A * C;
    if (disc < 0) return std::numeric_limits<double>::infinity();
    lambda = (-B - std::sqrt(disc)) / (2 * A);
    if (lambda < 0 || lambda > 1) return std::numeric_limits<double>::infinity();
  }
  const double z = path(i, 2) + lambda * (path(i + 1, 2) - path(i, 2));
  if (z > point.z() + z_tolerance) return std::numeric_limits<double>::infinity();
  return path(i, 3) + lambda * (path(i + 1, 3) - path(i, 3));
}

}  // namespace

double first_cover_time(const Eigen::MatrixXd& path, const std::vector<char>& cutting, const Eigen::Vector3d& point, double radius, double z_tolerance) {
  for (Eigen::Index i = 0; i + 1 < path.rows(); ++i) {
    if (!cutting.empty() && !cutting[static_cast<std::size_t>(i)]) continue;
    const double t = segment_cover_time(path, i, point, radius, z_tolerance);
    if (std::isfinite(t)) return t;  // segments come in time order
  }
  return std::numeric_limits<double>::infinity();
}

CutTimeIndex::CutTimeIndex(const Eigen::MatrixXd& path, double radius, double z_tolerance, double z_max)
    : path_(path), radius_(radius), z_tolerance_(z_tolerance), cell_(std::max(radius, 1e-6)) {
  std::vector<Eigen::Index> low;
  for (Eigen::Index i = 0; i + 1 < path.rows(); ++i)
    if (std::min(path(i, 2), path(i + 1, 2)) <= z_max) low.push_back(i);
  if (low.empty()) return;
  segments_.resize(static_cast<std::size_t>(path.rows() - 1));
  for (Eigen::Index i : low) {
    const double dx = path(i + 1, 0) - path(i, 0), dy = path(i + 1, 1) - path(i, 1);
    segments_[static_cast<std::size_t>(i)] = {path(i, 0), path(i, 1), dx, dy, dx * dx + dy * dy, path(i, 2), path(i + 1, 2), path(i, 3), path(i + 1, 3)};
  }
  double x1 = -1e300, y1 = -1e300;
  x0_ = y0_ = 1e300;
  for (Eigen::Index i : low)
    for (Eigen::Index j : {i, i + 1}) {
      x0_ = std::min(x0_, path(j, 0) - radius), y0_ = std::min(y0_, path(j, 1) - radius);
      x1 = std::max(x1, path(j, 0) + radius), y1 = std::max(y1, path(j, 1) + radius);
    }
  // At most 2048 x 2048 buckets: a path far larger than the tool (or a tiny radius) widens the cells
  // instead of asking for a grid past any memory, or past an int (the model_fields fuzzer, finding 19).
  // The buckets only index the segments: the distance tests below decide, whatever the cell size.
  constexpr double kMostCells = 2048;
  cell_ = std::max({cell_, (x1 - x0_) / kMostCells, (y1 - y0_) / kMostCells});
  nx_ = std::max(1, static_cast<int>(std::min(kMostCells, std::ceil((x1 - x0_) / cell_))));
  ny_ = std::max(1, static_cast<int>(std::min(kMostCells, std::ceil((y1 - y0_) / cell_))));
  buckets_.resize(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_));
  for (Eigen::Index i : low) {
    // Buckets within `radius` of the segment (its bounding box grown by the radius, then a distance test).
    const Eigen::Vector2d a = path.row(i).head<2>().transpose(), b = path.row(i + 1).head<2>().transpose();
    const int i0 = std::max(0, static_cast<int>((std::min(a.x(), b.x()) - radius - x0_) / cell_));
    const int i1 = std::min(nx_ - 1, static_cast<int>((std::max(a.x(), b.x()) + radius - x0_) / cell_));
    const int j0 = std::max(0, static_cast<int>((std::min(a.y(), b.y()) - radius - y0_) / cell_));
    const int j1 = std::min(ny_ - 1, static_cast<int>((std::max(a.y(), b.y()) + radius - y0_) / cell_));
    const Eigen::Vector2d d = b - a;
    for (int jj = j0; jj <= j1; ++jj)
      for (int ii = i0; ii <= i1; ++ii) {
        const Eigen::Vector2d centre(x0_ + (ii + 0.5) * cell_, y0_ + (jj + 0.5) * cell_);
        const double s = d.squaredNorm() > 0 ? std::clamp((centre - a).dot(d) / d.squaredNorm(), 0.0, 1.0) : 0.0;
        if ((a + s * d - centre).norm() > radius + 0.7072 * cell_) continue;  // half the cell's diagonal
        buckets_[static_cast<std::size_t>(jj) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(ii)].push_back(static_cast<int>(i));
      }
  }
}

// The bucket holding `point`, or false when it lies outside the grid (compared as doubles first: a
// far point's index would not fit an int).
bool CutTimeIndex::bucket_of(const Eigen::Vector3d& point, int& i, int& j) const {
  if (buckets_.empty()) return false;
  const double fi = std::floor((point.x() - x0_) / cell_), fj = std::floor((point.y() - y0_) / cell_);
  if (!(fi >= 0 && fj >= 0 && fi < nx_ && fj < ny_)) return false;
  i = static_cast<int>(fi), j = static_cast<int>(fj);
  return true;
}

double CutTimeIndex::at(const Eigen::Vector3d& point) const {
  int i = 0, j = 0;
  if (!bucket_of(point, i, j)) return std::numeric_limits<double>::infinity();
  double best = std::numeric_limits<double>::infinity();
  for (int s : buckets_[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i)]) {
    const double t = segment_cover_time(path_, s, point, radius_, z_tolerance_);
    if (t < best) best = t;
  }
  return best;
}

void CutTimeIndex::covers(const Eigen::Vector3d& point, double until, std::vector<std::pair<double, double>>& out) const {
  out.clear();
  int i = 0, j = 0;
  if (!bucket_of(point, i, j)) return;
  const double z_top = point.z() + z_tolerance_, r2 = radius_ * radius_;
  for (int s : buckets_[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i)]) {
    // The stretch of the segment during which the tool covers the point with its tip down: within
    // the radius (a quadratic in the segment's parameter), and where the tip is below z_top.
    const Segment& g = segments_[static_cast<std::size_t>(s)];
    if (g.t0 > until) break;  // a bucket's segments come in time order
    if (std::min(g.za, g.zb) > z_top) continue;
    const double fx = g.ax - point.x(), fy = g.ay - point.y();
    const double B = 2 * (fx * g.dx + fy * g.dy), C = fx * fx + fy * fy - r2;
    double lo = 0, hi = 1;
    if (g.A == 0) {
      if (C > 0) continue;
    } else {
      const double disc = B * B - 4 * g.A * C;
      if (disc < 0) continue;
      lo = std::max(lo, (-B - std::sqrt(disc)) / (2 * g.A));
      hi = std::min(hi, (-B + std::sqrt(disc)) / (2 * g.A));
    }
    if (g.za != g.zb) {
      const double l = (z_top - g.za) / (g.zb - g.za);
      if (g.zb > g.za) hi = std::min(hi, l);
      else lo = std::max(lo, l);
    }
    if (lo > hi) continue;
    const double entry = g.t0 + lo * (g.t1 - g.t0);
    if (entry > until) continue;
    out.emplace_back(entry, std::min(g.t0 + hi * (g.t1 - g.t0), until));
  }
}

}  // namespace drom::reduce
