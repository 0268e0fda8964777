#include "geometry/cloud_bins.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace drom::geometry {

namespace {
constexpr double kNone = -std::numeric_limits<double>::infinity();
// Cell rectangles are widened by this much (mm) in every test, so a point a rounding error outside its
// cell's nominal rectangle is never skipped.
constexpr double kSlack = 1e-7;
}

CloudBins::CloudBins(std::span<const Eigen::Vector3d> points, double cell) {
  if (!(cell > 0) || !std::isfinite(cell)) throw std::invalid_argument("CloudBins: the cell size must be positive");
  if (points.empty()) return;
  double x_min = points[0].x(), x_max = x_min, y_min = points[0].y(), y_max = y_min;
  for (const auto& p : points) {
    x_min = std::min(x_min, p.x()), x_max = std::max(x_max, p.x());
    y_min = std::min(y_min, p.y()), y_max = std::max(y_max, p.y());
  }
  const double area = (x_max - x_min + cell) * (y_max - y_min + cell);
  constexpr double kMaxCells = 16e6;
  if (area / (cell * cell) > kMaxCells) cell = std::sqrt(area / kMaxCells);
  cell_ = cell;
  x0_ = x_min, y0_ = y_min;
  nx_ = static_cast<int>(std::floor((x_max - x_min) / cell)) + 1;
  ny_ = static_cast<int>(std::floor((y_max - y_min) / cell)) + 1;
  const std::size_t cells = static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_);
  std::vector<std::uint32_t> id(points.size());
  start_.assign(cells + 1, 0);
  for (std::size_t k = 0; k < points.size(); ++k) {
    const int i = std::min(nx_ - 1, static_cast<int>((points[k].x() - x0_) / cell_));
    const int j = std::min(ny_ - 1, static_cast<int>((points[k].y() - y0_) / cell_));
    id[k] = static_cast<std::uint32_t>(cell_id(i, j));
    ++start_[id[k] + 1];
  }
  for (std::size_t c = 0; c < cells; ++c) start_[c + 1] += start_[c];
  points_.resize(points.size());
  std::vector<std::size_t> next(start_.begin(), start_.end() - 1);
  std::vector<double> top(cells, kNone);
  for (std::size_t k = 0; k < points.size(); ++k) {
    points_[next[id[k]]++] = {points[k].x(), points[k].y(), points[k].z(), static_cast<int>(k)};
    top[id[k]] = std::max(top[id[k]], points[k].z());
  }
  levels_.push_back(std::move(top));
  level_nx_.push_back(nx_), level_ny_.push_back(ny_);
  while (level_nx_.back() > 1 || level_ny_.back() > 1) {
    const int px = level_nx_.back(), py = level_ny_.back(), qx = (px + 1) / 2, qy = (py + 1) / 2;
    const auto& below = levels_.back();
    std::vector<double> up(static_cast<std::size_t>(qx) * static_cast<std::size_t>(qy), kNone);
    for (int j = 0; j < py; ++j)
      for (int i = 0; i < px; ++i) {
        double& u = up[static_cast<std::size_t>(j / 2) * static_cast<std::size_t>(qx) + static_cast<std::size_t>(i / 2)];
        u = std::max(u, below[static_cast<std::size_t>(j) * static_cast<std::size_t>(px) + static_cast<std::size_t>(i)]);
      }
    levels_.push_back(std::move(up));
    level_nx_.push_back(qx), level_ny_.push_back(qy);
  }
}

bool CloudBins::cell_range(double x, double y, double r, int& i0, int& i1, int& j0, int& j1) const {
  return !points_.empty() && block_range(0, x, y, r, i0, i1, j0, j1);
}

double CloudBins::cell_distance2(int i, int j, double x, double y) const { return block_distance2(0, i, j, x, y); }

double CloudBins::block_distance2(int l, int i, int j, double x, double y) const {
  const double size = cell_ * static_cast<double>(1 << l);
  const double lx = x0_ + i * size - kSlack, ly = y0_ + j * size - kSlack, w = size + 2 * kSlack;
  const double dx = std::max({lx - x, 0.0, x - (lx + w)}), dy = std::max({ly - y, 0.0, y - (ly + w)});
  return dx * dx + dy * dy;
}

double CloudBins::block_far_distance2(int l, int i, int j, double x, double y) const {
  const double size = cell_ * static_cast<double>(1 << l);
  const double lx = x0_ + i * size - kSlack, ly = y0_ + j * size - kSlack, w = size + 2 * kSlack;
  const double dx = std::max(std::abs(x - lx), std::abs(x - (lx + w))), dy = std::max(std::abs(y - ly), std::abs(y - (ly + w)));
  return dx * dx + dy * dy;
}

int CloudBins::start_level(double r) const {
  // The level whose blocks are about the disk's radius: a handful of blocks cover it.
  int l = 0;
  while (l + 1 < static_cast<int>(levels_.size()) && cell_ * static_cast<double>(1 << (l + 1)) <= r) ++l;
  return l;
}

void CloudBins::max_in_block(int l, int i, int j, double x, double y, double r2, double& best) const {
  if (i >= level_nx_[static_cast<std::size_t>(l)] || j >= level_ny_[static_cast<std::size_t>(l)]) return;
  const double m = level_max(l, i, j);
  if (m <= best || block_distance2(l, i, j, x, y) > r2) return;
  if (block_far_distance2(l, i, j, x, y) <= r2) {  // the whole block lies inside the disk
    best = m;
    return;
  }
  if (l == 0) {
    for (const auto& p : cell_points(i, j)) {
      const double dx = p.x - x, dy = p.y - y;
      if (dx * dx + dy * dy <= r2 && p.z > best) best = p.z;
    }
    return;
  }
  for (int b = 0; b < 2; ++b)
    for (int a = 0; a < 2; ++a) max_in_block(l - 1, 2 * i + a, 2 * j + b, x, y, r2, best);
}

bool CloudBins::above_in_block(int l, int i, int j, double x, double y, double r2, double z) const {
  if (i >= level_nx_[static_cast<std::size_t>(l)] || j >= level_ny_[static_cast<std::size_t>(l)]) return false;
  if (level_max(l, i, j) <= z || block_distance2(l, i, j, x, y) >= r2) return false;
  if (block_far_distance2(l, i, j, x, y) < r2) return true;
  if (l == 0) {
    for (const auto& p : cell_points(i, j)) {
      const double dx = p.x - x, dy = p.y - y;
      if (p.z > z && dx * dx + dy * dy < r2) return true;
    }
    return false;
  }
  for (int b = 0; b < 2; ++b)
    for (int a = 0; a < 2; ++a)
      if (above_in_block(l - 1, 2 * i + a, 2 * j + b, x, y, r2, z)) return true;
  return false;
}

bool CloudBins::block_range(int l, double x, double y, double r, int& i0, int& i1, int& j0, int& j1) const {
  const double size = cell_ * static_cast<double>(1 << l);
  const int nx = level_nx_[static_cast<std::size_t>(l)], ny = level_ny_[static_cast<std::size_t>(l)];
  const double a0 = std::floor((x - r - kSlack - x0_) / size), a1 = std::floor((x + r + kSlack - x0_) / size);
  const double b0 = std::floor((y - r - kSlack - y0_) / size), b1 = std::floor((y + r + kSlack - y0_) / size);
  if (!(a1 >= 0 && b1 >= 0 && a0 <= nx - 1 && b0 <= ny - 1)) return false;  // also false on NaN
  i0 = static_cast<int>(std::max(0.0, a0)), i1 = static_cast<int>(std::min<double>(nx - 1, a1));
  j0 = static_cast<int>(std::max(0.0, b0)), j1 = static_cast<int>(std::min<double>(ny - 1, b1));
  return true;
}

double CloudBins::max_z_within(double x, double y, double r, double above) const {
  double best = std::max(kNone, above);
  int i0, i1, j0, j1;
  if (points_.empty() || !(r >= 0)) return best;
  const int l = start_level(r);
  if (!block_range(l, x, y, r, i0, i1, j0, j1)) return best;
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) max_in_block(l, i, j, x, y, r * r, best);
  return best;
}

bool CloudBins::any_above(double x, double y, double r, double z) const {
  int i0, i1, j0, j1;
  if (points_.empty() || !(r > 0)) return false;
  const int l = start_level(r);
  if (!block_range(l, x, y, r, i0, i1, j0, j1)) return false;
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i)
      if (above_in_block(l, i, j, x, y, r * r, z)) return true;
  return false;
}

void CloudBins::within(double x, double y, double r, std::vector<int>& out) const {
  out.clear();
  int i0, i1, j0, j1;
  if (!cell_range(x, y, r, i0, i1, j0, j1)) return;
  const double r2 = r * r;
  for (int j = j0; j <= j1; ++j)
    for (int i = i0; i <= i1; ++i) {
      if (block_distance2(0, i, j, x, y) > r2) continue;
      for (const auto& p : cell_points(i, j)) {
        const double dx = p.x - x, dy = p.y - y;
        if (dx * dx + dy * dy <= r2) out.push_back(p.index);
      }
    }
}

}  // namespace drom::geometry
