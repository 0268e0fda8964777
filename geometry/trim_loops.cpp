#include "geometry/trim_loops.hpp"

#include <stdexcept>

namespace drom::geometry {

TrimLoops::TrimLoops(std::vector<std::vector<Eigen::Vector2d>> loops) : loops_(std::move(loops)) {
  for (const auto& loop : loops_)
    if (loop.size() < 3) throw std::invalid_argument("a trimming loop needs at least 3 points");
}

bool TrimLoops::contains(double u, double v) const {
  if (loops_.empty()) return true;
  bool inside = false;
  for (const auto& loop : loops_) {
    const std::size_t n = loop.size();
    for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
      const Eigen::Vector2d &a = loop[i], &b = loop[j];
      if ((a.y() > v) != (b.y() > v) && u < a.x() + (v - a.y()) * (b.x() - a.x()) / (b.y() - a.y())) inside = !inside;
    }
  }
  return inside;
}

}  // namespace drom::geometry
