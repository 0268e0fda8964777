#include "paths/copy/cloud_area.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace drom::paths {

CloudArea::CloudArea(std::span<const Eigen::Vector3d> points, double cell, double margin) {
  if (!(cell > 0)) throw std::invalid_argument("CloudArea: the cell must be positive");
  if (points.empty()) return;
  double lx = std::numeric_limits<double>::infinity(), ly = lx, hx = -lx, hy = -lx;
  for (const auto& p : points) lx = std::min(lx, p.x()), hx = std::max(hx, p.x()), ly = std::min(ly, p.y()), hy = std::max(hy, p.y());
  const int grow = static_cast<int>(std::ceil(margin / cell));
  // Enlarge the cell where the grid would be huge (a speed and memory guard; the area only grows).
  while ((hx - lx) / cell * (hy - ly) / cell > 4e7) cell *= 2;
  cell_ = cell;
  x0_ = lx - (grow + 1) * cell, y0_ = ly - (grow + 1) * cell;
  nx_ = static_cast<int>(std::floor((hx - x0_) / cell)) + grow + 2;
  ny_ = static_cast<int>(std::floor((hy - y0_) / cell)) + grow + 2;
  std::vector<char> seed(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_), 0);
  for (const auto& p : points) {
    const int i = static_cast<int>((p.x() - x0_) / cell), j = static_cast<int>((p.y() - y0_) / cell);
    seed[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i)] = 1;
  }
  inside_.assign(seed.size(), 0);
  std::vector<std::pair<int, int>> disk;
  const double reach = margin / cell + 1e-9;
  for (int b = -grow; b <= grow; ++b)
    for (int a = -grow; a <= grow; ++a)
      if (a * a + b * b <= reach * reach) disk.emplace_back(a, b);
  x_min_ = y_min_ = std::numeric_limits<double>::infinity(), x_max_ = y_max_ = -x_min_;
  for (int j = 0; j < ny_; ++j)
    for (int i = 0; i < nx_; ++i) {
      if (!seed[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i)]) continue;
      for (const auto& [a, b] : disk) {
        const int u = i + a, v = j + b;
        if (u < 0 || v < 0 || u >= nx_ || v >= ny_) continue;
        char& c = inside_[static_cast<std::size_t>(v) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(u)];
        if (!c) {
          c = 1;
          ++count_;
          x_min_ = std::min(x_min_, x0_ + u * cell), x_max_ = std::max(x_max_, x0_ + (u + 1) * cell);
          y_min_ = std::min(y_min_, y0_ + v * cell), y_max_ = std::max(y_max_, y0_ + (v + 1) * cell);
        }
      }
    }
}

CloudArea CloudArea::rectangle(double x0, double x1, double y0, double y1) {
  CloudArea a;
  if (!(x1 > x0) || !(y1 > y0)) return a;
  a.x_min_ = a.x0_ = x0, a.x_max_ = x1, a.y_min_ = a.y0_ = y0, a.y_max_ = y1;
  a.count_ = 1;
  return a;
}

bool CloudArea::contains(double x, double y) const {
  if (count_ == 0 || !(x >= x_min_ && x <= x_max_ && y >= y_min_ && y <= y_max_)) return false;
  if (inside_.empty()) return true;
  const int i = static_cast<int>((x - x0_) / cell_), j = static_cast<int>((y - y0_) / cell_);
  if (i < 0 || j < 0 || i >= nx_ || j >= ny_) return false;
  return inside_[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i)] != 0;
}

double CloudArea::area() const {
  if (inside_.empty()) return count_ ? (x_max_ - x_min_) * (y_max_ - y_min_) : 0.0;
  return static_cast<double>(count_) * cell_ * cell_;
}

}  // namespace drom::paths
