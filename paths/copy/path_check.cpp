#include "paths/copy/path_check.hpp"

#include "paths/copy/tool_drop.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>

namespace drom::paths {

namespace {

// How deep the tool with its tip at `tip` stands inside the points: the cutter by where it would
// stand dropped there (every point under it, the same drop the bins give the paths, which the tests
// hold to brute force bit for bit), the shank and the holder by the highest point under them.
double depth_at(const geometry::CloudBins& bins, const Eigen::Vector3d& tip, const ToolAssembly& tool) {
  const Drop cutter = drop_tool(bins, tip.x(), tip.y(), tool.cutter);
  double deepest = cutter.contact ? cutter.tip - tip.z() : -1e300;
  // The shank and the holder only matter where they stand deeper than the cutter: their queries
  // read no block lower than that (less a margin for the rounding of the sums).
  const auto deeper = [&](double height) { return deepest + tip.z() + height - 1e-9 * (1 + std::abs(tip.z()) + height); };
  if (tool.shank() > tool.cutter.radius) deepest = std::max(deepest, bins.max_z_within(tip.x(), tip.y(), tool.shank(), deeper(tool.flutes())) - tip.z() - tool.flutes());
  if (tool.has_holder()) deepest = std::max(deepest, bins.max_z_within(tip.x(), tip.y(), tool.holder_reach(), deeper(tool.gauge_length)) - tip.z() - tool.gauge_length);
  return deepest;
}

}  // namespace

PathCheck check_path(const geometry::CloudBins& bins, const CloudPath& path, const ToolAssembly& tool, double spacing, double tolerance) {
  PathCheck out;
  std::mutex lock;
  tbb::parallel_for(std::size_t(0), path.size(), [&](std::size_t i) {
    PathCheck local;
    const Eigen::Vector3d b = path.tips[i];
    const Eigen::Vector3d a = i > 0 ? path.tips[i - 1] : b;
    const int samples = i > 0 ? std::max(1, static_cast<int>(std::ceil((b - a).norm() / spacing))) : 1;
    const double allowed = path.motion[i] == Motion::rapid ? 1e-9 : tolerance + 1e-9;
    // A cut node the planner dropped (it carries its contact normal) stands at the whole tool's drop
    // there by construction: the check looks between such nodes, and at every other point.
    const bool dropped = path.motion[i] == Motion::cut && path.normals[i].squaredNorm() > 0;
    for (int k = 1; k <= samples - (dropped && samples > 1 ? 1 : 0); ++k) {
      const Eigen::Vector3d p = a + (b - a) * (static_cast<double>(k) / samples);
      const double d = depth_at(bins, p, tool);
      ++local.positions;
      if (d > local.deepest) local.deepest = d, local.worst = p;
      if (d > allowed) ++local.over;
    }
    std::lock_guard guard(lock);
    out.positions += local.positions, out.over += local.over;
    if (local.deepest > out.deepest) out.deepest = local.deepest, out.worst = local.worst;
  });
  return out;
}

std::string refusal(const PathCheck& check, const Eigen::Matrix3d& frame, double tolerance) {
  if (check.over == 0) return {};
  const Eigen::Vector3d part = frame.transpose() * check.worst;
  char what[320];
  std::snprintf(what, sizeof what,
                "%lld tool positions stand deeper than %.4g mm into the scan (the deepest %.4f mm, tip at (%.3f, %.3f, %.3f) in the part frame): the program is not posted",
                check.over, tolerance, check.deepest, part.x(), part.y(), part.z());
  return what;
}

}  // namespace drom::paths
