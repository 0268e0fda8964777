#include "loop/replanned_finish.hpp"

#include "geometry/cloud_bins.hpp"
#include "paths/copy/cloud_area.hpp"
#include "paths/copy/tool_drop.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace drom::loop {

ReplanSettings::ReplanSettings() {
  finishing.tool.cutter = {paths::ToolKind::ball, 5, 5};
  finishing.longitudinal_step = 1;
  finishing.chord_tolerance = 0.002;
  finishing.scallop = 0.002;
}

std::vector<Eigen::Vector3d> upward_surface_cloud(const online::FinalShape& shape, const Eigen::Matrix3Xd& displacement, double spacing, double min_up, long long* faces) {
  if (displacement.cols() != shape.nodes.cols()) throw std::invalid_argument("upward_surface_cloud: one displacement per node");
  // Quadratic faces (8-node quads, 6-node triangles) list their corners first: the corners span the
  // face (its mid-side nodes' displacement is left to the bilinear/linear interpolation).
  const int stride = shape.face_nodes;
  const int m = stride >= 8 ? 4 : stride == 6 ? 3 : stride;
  if (m != 3 && m != 4) throw std::invalid_argument("upward_surface_cloud: faces of 3, 4, 6 or 8 nodes");
  std::vector<Eigen::Vector3d> cloud;
  long long count = 0;
  for (std::size_t f = 0; f + static_cast<std::size_t>(stride) <= shape.faces.size(); f += static_cast<std::size_t>(stride)) {
    Eigen::Vector3d x[4], u[4];
    for (int k = 0; k < m; ++k) {
      const int node = shape.faces[f + static_cast<std::size_t>(k)];
      x[k] = shape.nodes.col(node), u[k] = displacement.col(node);
    }
    const Eigen::Vector3d normal = (x[1] - x[0]).cross(x[m - 1] - x[0]);
    // Outward normals: the part's bottom, never the highest over its xy, would double the cloud for
    // nothing (and poke out past the bent top's edge, where the side is).
    if (!(normal.norm() > 0) || normal.z() < min_up * normal.norm()) continue;
    ++count;
    const double size = std::max((x[1] - x[0]).norm(), (x[m - 1] - x[0]).norm());
    const int n = std::max(1, static_cast<int>(std::ceil(size / spacing)));
    // Interior and edge samples alike: the shared edges' points come twice, which the drop ignores.
    for (int i = 0; i <= n; ++i)
      for (int j = 0; j <= (m == 4 ? n : n - i); ++j) {
        const double a = static_cast<double>(i) / n, b = static_cast<double>(j) / n;
        Eigen::Vector3d p;
        if (m == 4) {
          const double w[4] = {(1 - a) * (1 - b), a * (1 - b), a * b, (1 - a) * b};
          p.setZero();
          for (int k = 0; k < 4; ++k) p += w[k] * (x[k] + u[k]);
        } else {
          p = (1 - a - b) * (x[0] + u[0]) + a * (x[1] + u[1]) + b * (x[2] + u[2]);
        }
        cloud.push_back(p);
      }
  }
  if (faces) *faces = count;
  return cloud;
}

double sample_spacing(const ReplanSettings& s) {
  if (s.sample_spacing > 0) return s.sample_spacing;
  return std::sqrt(8 * s.finishing.tool.cutter.radius * s.finishing.chord_tolerance);
}

ReplannedFinish replan_finish(const online::FinalShape& shape, const Eigen::Matrix3Xd& truth, const ReplanSettings& s) {
  ReplannedFinish out;
  const double spacing = sample_spacing(s);
  if (!(spacing > 0) || !std::isfinite(spacing)) throw std::invalid_argument("replan_finish: the sample spacing must be positive");
  const Eigen::Matrix3Xd zero = Eigen::Matrix3Xd::Zero(3, shape.nodes.cols());
  const auto predicted = upward_surface_cloud(shape, shape.displacement, spacing, s.min_up, &out.faces);
  const auto true_cloud = upward_surface_cloud(shape, truth, spacing, s.min_up);
  const auto drawn = upward_surface_cloud(shape, zero, spacing, s.min_up);
  out.cloud_points = static_cast<long long>(predicted.size());
  const double cell = std::max(spacing, s.finishing.tool.cutter.radius / 2);
  const geometry::CloudBins bins(predicted, cell), true_bins(true_cloud, cell), drawn_bins(drawn, cell);
  // The area: where the drawn part has an upward face (its outline, no margin: the tool stays on it).
  const paths::CloudArea area(drawn, s.finishing.longitudinal_step, 0);
  out.replanned = paths::plan_cloud_finishing(bins, area, s.finishing);
  double sum = 0, nominal_sum = 0;
  const auto& path = out.replanned.path;
  for (std::size_t i = 0; i < path.size(); ++i) {
    if (path.motion[i] != paths::Motion::cut) continue;
    const Eigen::Vector3d& tip = path.tips[i];
    const paths::Drop on_truth = paths::drop_tool(true_bins, tip.x(), tip.y(), s.finishing.tool.cutter);
    const paths::Drop on_drawing = paths::drop_tool(drawn_bins, tip.x(), tip.y(), s.finishing.tool.cutter);
    if (!on_truth.contact || !on_drawing.contact) continue;
    const double e = tip.z() - on_truth.tip, nominal = on_drawing.tip - on_truth.tip;
    ++out.judged;
    out.max_error = std::max(out.max_error, std::abs(e)), sum += e * e;
    out.nominal_max_error = std::max(out.nominal_max_error, std::abs(nominal)), nominal_sum += nominal * nominal;
  }
  if (out.judged > 0) {
    out.rms_error = std::sqrt(sum / static_cast<double>(out.judged));
    out.nominal_rms_error = std::sqrt(nominal_sum / static_cast<double>(out.judged));
  }
  return out;
}

}  // namespace drom::loop
