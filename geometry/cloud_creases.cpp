#include "geometry/cloud_creases.hpp"

#include "geometry/cloud_cells.hpp"

#include <Eigen/Dense>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <numbers>

namespace drom::geometry {

Creases crease_points(std::span<const Eigen::Vector3d> points, double noise, double spacing) {
  if (points.size() < 30 || !(spacing > 0)) return {};
  return crease_points(points, ScanSurvey(points), noise, spacing);
}

Creases crease_points(std::span<const Eigen::Vector3d> points, const ScanSurvey& survey, double noise, double spacing) {
  Creases out;
  if (points.size() < 30 || !(spacing > 0) || !(survey.spacing > 0)) return out;
  const CloudCells& cells = survey.cells;
  out.cell = cells.cell;
  const double flat = flat_face_residual(noise);
  std::vector<std::vector<Eigen::Vector3d>> found(cells.centroids.size());
  tbb::parallel_for(std::size_t(0), cells.centroids.size(), [&](std::size_t i) {
    // The cell's points and its neighbours', at most about 400.
    std::size_t total = cells.members[i].size();
    for (const int k : cells.neighbours[i]) total += cells.members[static_cast<std::size_t>(k)].size();
    const std::size_t stride = std::max<std::size_t>(1, total / 400);
    std::vector<Eigen::Vector3d> q;
    std::size_t seen = 0;
    const auto take = [&](const std::vector<int>& members) {
      for (const int m : members)
        if (seen++ % stride == 0) q.push_back(points[static_cast<std::size_t>(m)]);
    };
    take(cells.members[i]);
    for (const int k : cells.neighbours[i]) take(cells.members[static_cast<std::size_t>(k)]);
    if (q.size() < 20) return;
    const LocalPlane frame = fit_plane(q);
    if (std::sqrt(frame.spread[0]) <= flat) return;     // flat: no crease
    // Curved but smooth: a quadric leaves the noise alone. Not `flat` (three deviations): a crest
    // whose neighbourhood a quadric misses by less than that (a ridge at 38 degrees under 0.035 mm of
    // noise) would go unseen, and the tool would ride over the points beside it, below the crest.
    const double smooth = fit_quadric(q, frame);
    if (smooth <= 1.5 * noise + 0.005) return;
    const TwoPlanes two = fit_two_planes(q, frame, 2.5 * out.cell, flat, smooth);
    if (!two.found) return;
    const Eigen::Vector3d t = two.line_direction, x0 = two.line_point;
    // The line must run through this cell's points (a crease here, not one extrapolated to).
    const Eigen::Vector3d& centroid = cells.centroids[i];
    const Eigen::Vector3d off = (centroid - x0) - (centroid - x0).dot(t) * t;
    if (off.norm() > out.cell) return;
    // Over the cell's extent along the line, and half a cell beyond either end: the segments of
    // neighbouring cells overlap, and a cell the test missed leaves no gap in the line.
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (const int mbr : cells.members[i]) {
      const double along = (points[static_cast<std::size_t>(mbr)] - x0).dot(t);
      lo = std::min(lo, along), hi = std::max(hi, along);
    }
    lo -= 0.5 * out.cell, hi += 0.5 * out.cell;
    const int n = std::max(1, static_cast<int>(std::ceil((hi - lo) / spacing)));
    // Three times the line's own uncertainty above and below it, along the planes' bisector: the tool
    // rests on the higher, and leaves stock where the crease is unsure rather than cutting it.
    // (Without it, and with the planes fitted on every point, a ridge at 35 degrees under 0.05 mm of
    // noise came back up to 0.04 mm low: tests/geometry/cloud_creases_test.cpp.)
    Eigen::Vector3d nb = two.normal_b;
    if (nb.dot(two.normal_a) < 0) nb = -nb;
    const Eigen::Vector3d bisector = (two.normal_a + nb).normalized();
    for (int k = 0; k <= n; ++k) {
      const Eigen::Vector3d on = x0 + (lo + (hi - lo) * k / n) * t;
      // Never more than three noise deviations: a line no better known than one scanned point.
      const double lift = std::min(3 * two.line_uncertainty(on), 3 * two.residual);
      if (lift > 1e-9) {
        found[i].push_back(on + lift * bisector), found[i].push_back(on - lift * bisector);
      } else {
        found[i].push_back(on);
      }
    }
  });
  for (std::size_t i = 0; i < found.size(); ++i) {
    if (found[i].empty()) continue;
    ++out.cells;
    out.points.insert(out.points.end(), found[i].begin(), found[i].end());
    out.source.insert(out.source.end(), found[i].size(), cells.members[i].front());
  }
  return out;
}

}  // namespace drom::geometry
