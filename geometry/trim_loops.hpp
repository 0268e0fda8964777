#pragma once
// A trimmed patch's boundary in its parameter domain: closed polygons in (u, v), the outer loop and
// any holes, tested with the even-odd rule. No loops means the whole domain.
#include <Eigen/Core>

#include <vector>

namespace drom::geometry {

class TrimLoops {
 public:
  TrimLoops() = default;
  explicit TrimLoops(std::vector<std::vector<Eigen::Vector2d>> loops);

  bool empty() const { return loops_.empty(); }
  const std::vector<std::vector<Eigen::Vector2d>>& loops() const { return loops_; }
  // Whether (u, v) lies inside: an odd number of loop crossings on a ray towards +u.
  bool contains(double u, double v) const;

 private:
  std::vector<std::vector<Eigen::Vector2d>> loops_;
};

}  // namespace drom::geometry
