#include "geometry/cloud_noise_floor.hpp"

#include "geometry/cloud_kdtree.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace drom::geometry {

NoiseFloor noise_floor(std::span<const Eigen::Vector3d> points, const ScanSurvey& survey, double noise) {
  NoiseFloor out;
  constexpr std::size_t neighbours = 40;
  if (!(3 * noise > 0.005) || points.size() < neighbours) return out;
  // What a smooth face leaves over 40 points: the noise, give or take 0.12 of it (the hole filling's
  // test, geometry/cloud_holes.cpp); a crease, an edge or another face among them leaves more.
  const double smooth = 1.3 * noise + 0.002;
  struct Fit {
    Eigen::Vector3d on = Eigen::Vector3d::Zero(), normal = Eigen::Vector3d::Zero();
    double sd = -1;  // < 0: no smooth fit here
  };
  std::vector<Fit> fits(points.size());
  tbb::parallel_for(std::size_t(0), points.size(), [&](std::size_t i) {
    std::vector<int> near;
    std::vector<double> d2;
    survey.tree.nearest(points[i], static_cast<int>(neighbours), near, d2);
    if (near.size() < neighbours) return;
    std::vector<Eigen::Vector3d> q;
    q.reserve(near.size());
    for (const int j : near) q.push_back(points[static_cast<std::size_t>(j)]);
    const LocalSurface local(q, smooth);
    // A quadric, or beside a crease (where the 40 straddle it and no quadric fits) the plane of the
    // point's own side: a ridge's flank 0.3 mm from its crest had no floor, and the ball resting on the
    // crest's line and the flank's low points went 0.013 mm into the flank (issue 45, seed 4242).
    const Eigen::Vector2d at = local.uv(points[i]);
    const std::optional<LocalSurface::Spot> spot = local.spot(at);
    if (!spot) return;
    // The point amid its neighbours (at a rim they all lie to one side, and the fit extrapolates).
    if (!(spot->leverage <= 1)) return;
    // The noise here: the scan's (a median over it) or what this fit leaves, the larger. Noise along
    // a sensor's line of sight reads larger where the face looks at it (a ball's top under 0.01 mm
    // read 0.0077 over the whole ball, and the floor stood 0.004 mm under its top).
    const double here = std::max(noise, spot->residual);
    fits[i] = {spot->on, spot->normal, here * std::sqrt(spot->leverage)};
  });
  for (const Fit& f : fits) out.fits += f.sd >= 0 ? 1 : 0;
  // The lift is set so that the lowest of the fits stays above the surface (geometry/cloud_cells.hpp).
  // Neighbouring fits share most of their points, but counting one in 40 as standing on its own (3.45
  // deviations for 14 000 points, where all give 4.46) left the floor 0.01 mm under a ball's true
  // surface under 0.08 mm of noise (tests/geometry/cloud_noise_floor_test.cpp).
  out.deviations = safe_lift_deviations(out.fits);
  out.points.reserve(2 * out.fits), out.source.reserve(2 * out.fits);
  for (std::size_t i = 0; i < fits.size(); ++i) {
    if (fits[i].sd < 0) continue;
    const double lift = out.deviations * fits[i].sd;
    out.points.push_back(fits[i].on + lift * fits[i].normal), out.points.push_back(fits[i].on - lift * fits[i].normal);
    out.source.insert(out.source.end(), 2, static_cast<int>(i));
  }
  return out;
}

}  // namespace drom::geometry
