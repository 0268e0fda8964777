#include "geometry/cloud_creases.hpp"

#include "geometry/cloud_cells.hpp"
#include "geometry/cloud_kdtree.hpp"

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
  // Under noise a neighbourhood of 2.5 cells is too small to tell a crest from a quadric: over a disc
  // of radius r, a quadric misses faces meeting with slopes +-m about their bisector by 0.071 m r
  // (rms), and a ridge at 24 degrees under 0.072 mm of noise on a 0.25 mm grid (issue 45's ridge 4)
  // went unseen at 0.94 mm; the tool rode the points beside the crest, 0.061 mm under it. Where a cell
  // shows nothing, its points within `wide` are read again: the radius at which faces meeting at 30
  // degrees stand one noise deviation off the quadric (at 45 degrees a ridge at 15 degrees under 0.032
  // mm of noise went unseen, 0.013 mm cut). There the quadric's residual is not held to the
  // noise's (a deviation is all it stands off) but the two planes must leave less than it by five of
  // the residual ratio's own deviations (1 / sqrt(2 n) over n points).
  const double wide = noise / (0.071 * std::tan(15 * std::numbers::pi / 180));
  const bool look_wider = wide > 2.5 * out.cell;
  std::vector<std::vector<Eigen::Vector3d>> found(cells.centroids.size());
  tbb::parallel_for(std::size_t(0), cells.centroids.size(), [&](std::size_t i) {
    // The cell's points and its neighbours', at most about 400.
    std::size_t total = cells.members[i].size();
    for (const int k : cells.neighbours[i]) total += cells.members[static_cast<std::size_t>(k)].size();
    std::size_t stride = std::max<std::size_t>(1, total / 400);
    std::vector<Eigen::Vector3d> q;
    std::size_t seen = 0;
    const auto take = [&](const std::vector<int>& members) {
      for (const int m : members)
        if (seen++ % stride == 0) q.push_back(points[static_cast<std::size_t>(m)]);
    };
    take(cells.members[i]);
    for (const int k : cells.neighbours[i]) take(cells.members[static_cast<std::size_t>(k)]);
    const auto crease_in = [&](std::span<const Eigen::Vector3d> around, double reach, bool widened) {
      TwoPlanes none;
      if (around.size() < 20) return none;
      const LocalPlane frame = fit_plane(around);
      if (std::sqrt(frame.spread[0]) <= flat) return none;  // flat: no crease
      // Curved but smooth: a quadric leaves the noise alone. Not `flat` (three deviations): a crest
      // whose neighbourhood a quadric misses by less than that (a ridge at 38 degrees under 0.035 mm
      // of noise) would go unseen, and the tool would ride over the points beside it, below the crest.
      const double smooth = fit_quadric(around, frame);
      if (!widened) return smooth <= 1.5 * noise + 0.005 ? none : fit_two_planes(around, frame, reach, flat, smooth);
      return fit_two_planes(around, frame, reach, flat, smooth, 1 / (1 + 5 / std::sqrt(2.0 * static_cast<double>(around.size()))));
    };
    TwoPlanes two = crease_in(q, 2.5 * out.cell, false);
    if (!two.found && look_wider) {
      std::vector<int> near;
      survey.tree.within(cells.centroids[i], wide, near);
      stride = std::max<std::size_t>(1, near.size() / 400);
      q.clear();
      for (std::size_t m = 0; m < near.size(); m += stride) q.push_back(points[static_cast<std::size_t>(near[m])]);
      two = crease_in(q, wide, true);
    }
    if (!two.found) return;
    const Eigen::Vector3d t = two.line_direction, x0 = two.line_point;
    // The line must run through this cell's points (a crease here, not one extrapolated to): within
    // 1.5 cells of one of them. (Within a cell of their centroid, a crest scanned at random every 0.76
    // mm fell between the cells along it, their centroids on the flanks, and went 1.5 mm without a line.)
    double off = std::numeric_limits<double>::infinity();
    for (const int mbr : cells.members[i]) {
      const Eigen::Vector3d d = points[static_cast<std::size_t>(mbr)] - x0;
      off = std::min(off, (d - d.dot(t) * t).norm());
    }
    if (off > 1.5 * out.cell) return;
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
    // Each plane's normal turned away from the other plane's points, so that their sum is the wedge's
    // own axis whatever their angle. (Turning them to a positive dot product chose the other bisector
    // where the faces meet at under 90°: a ridge's flanks steeper than 45° were lifted sideways, along
    // the flanks, and the line stayed its own error under the crest; issue 45, seed 6060's ridge 0 at
    // 48°, 0.025 mm into the truth.)
    Eigen::Vector3d na = two.normal_a, nb = two.normal_b;
    if (na.dot(two.point_b - two.point_a) > 0) na = -na;
    if (nb.dot(two.point_a - two.point_b) > 0) nb = -nb;
    const Eigen::Vector3d bisector = (na + nb).normalized();
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
