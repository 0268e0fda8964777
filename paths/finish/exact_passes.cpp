#include "paths/finish/exact_passes.hpp"

#include "geometry/local_geometry.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace drom::paths {

namespace {

struct Node {
  double u, v;
  Eigen::Vector3d point;
};

SurfaceContact contact(const geometry::NurbsSurface& s, double u, double v, const Eigen::Vector3d& reference) {
  const auto g = geometry::local_geometry(s.derivatives(u, v));
  const double sign = g.normal.dot(reference) < 0 ? -1.0 : 1.0;
  return {g.point, sign * g.normal, sign * g.curvature};
}

// The point of the iso-curve through the crossing where m . S = level.
Node on_iso_curve(const geometry::NurbsSurface& s, const Eigen::Vector3d& m, double level, const IsoCrossing& x) {
  double u = x.u, v = x.v;
  for (int it = 0; it < 12; ++it) {
    const auto d = s.derivatives(u, v);
    const double g = m.dot(d.point) - level, slope = m.dot(x.along_u ? d.du : d.dv);
    if (std::abs(g) < 1e-12 || slope == 0) break;
    double& t = x.along_u ? u : v;
    t = std::clamp(t - g / slope, x.lo, x.hi);
  }
  return {u, v, s.point(u, v)};
}

// The point of the plane's intersection curve halfway (along the chord) between a and b.
Node halfway(const geometry::NurbsSurface& s, const Eigen::Vector3d& m, double level, const Node& a, const Node& b) {
  const Eigen::Vector3d chord_mid = 0.5 * (a.point + b.point), d = (b.point - a.point).normalized();
  double u = 0.5 * (a.u + b.u), v = 0.5 * (a.v + b.v);
  for (int it = 0; it < 12; ++it) {
    const auto q = s.derivatives(u, v);
    const Eigen::Vector2d f(m.dot(q.point) - level, d.dot(q.point - chord_mid));
    if (f.norm() < 1e-12) break;
    Eigen::Matrix2d j;
    j << m.dot(q.du), m.dot(q.dv), d.dot(q.du), d.dot(q.dv);
    const Eigen::Vector2d step = j.fullPivLu().solve(f);
    if (!step.allFinite()) break;
    u = std::clamp(u - step(0), s.u_min(), s.u_max());
    v = std::clamp(v - step(1), s.v_min(), s.v_max());
  }
  return {u, v, s.point(u, v)};
}

void refine(const geometry::NurbsSurface& s, const Eigen::Vector3d& m, double level, const Node& a, const Node& b, double tolerance, int depth,
            std::vector<Node>& out) {
  if (depth > 0) {
    const Node mid = halfway(s, m, level, a, b);
    if ((mid.point - 0.5 * (a.point + b.point)).norm() > tolerance) {
      refine(s, m, level, a, mid, tolerance, depth - 1, out);
      refine(s, m, level, mid, b, tolerance, depth - 1, out);
      return;
    }
  }
  out.push_back(b);
}

}  // namespace

std::vector<SurfaceContact> exact_chain(const geometry::NurbsSurface& surface, const Eigen::Vector3d& plane_normal, double level,
                                        const std::vector<IsoCrossing>& chain, const std::vector<Eigen::Vector3d>& reference_normals, double tolerance) {
  std::vector<Node> nodes;
  std::vector<std::size_t> origin;  // which crossing each node is nearest to, for its reference normal
  for (std::size_t k = 0; k < chain.size(); ++k) {
    const Node n = on_iso_curve(surface, plane_normal, level, chain[k]);
    if (nodes.empty()) {
      nodes.push_back(n);
      origin.push_back(k);
      continue;
    }
    const std::size_t before = nodes.size();
    refine(surface, plane_normal, level, nodes.back(), n, tolerance, 8, nodes);
    for (std::size_t i = before; i < nodes.size(); ++i) origin.push_back(k);
  }
  std::vector<SurfaceContact> out;
  out.reserve(nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i) out.push_back(contact(surface, nodes[i].u, nodes[i].v, reference_normals[origin[i]]));
  return out;
}

std::vector<SurfaceContact> trace_on(const geometry::NurbsSurface& surface, TraceStart start, const TraceRules& rules) {
  const Eigen::Vector3d& m = rules.plane_normal;
  const Eigen::Vector3d& axis = rules.axis;
  const double level = rules.level, margin = rules.margin, max_length = rules.max_length, tolerance = rules.chord_tolerance;
  const auto& needed = rules.needed;
  Eigen::Vector2d& uv = start.uv;
  Eigen::Vector3d &point = start.point, &direction = start.direction, &reference = start.reference_normal;
  std::vector<SurfaceContact> out;
  if (!(direction.norm() > 0)) return out;  // no way out to follow
  const double span_u = surface.u_max() - surface.u_min(), span_v = surface.v_max() - surface.v_min();
  double traced = 0, until = std::min(margin, max_length);
  while (traced < max_length - 1e-9) {
    const auto d = surface.derivatives(uv.x(), uv.y());
    // Past the patch its continued polynomials can fold (or a rational patch's weights vanish):
    // the trace ends where the surface has no normal.
    geometry::LocalGeometry g;
    try {
      g = geometry::local_geometry(d);
    } catch (const std::domain_error&) {
      break;
    }
    const double sign = g.normal.dot(reference) < 0 ? -1.0 : 1.0;
    const SurfaceContact here{g.point, sign * g.normal, sign * g.curvature};
    Eigen::Vector3d t = m.cross(here.normal);
    if (t.norm() < 1e-9) break;
    t.normalize();
    if (t.dot(direction) < 0) t = -t;
    if (needed && needed({uv, d, t, here.normal})) until = std::min(max_length, traced + margin);
    if (traced >= until - 1e-9) break;
    // The chord's sagitta kappa h^2 / 8 within the tolerance; at most 1 mm (the mesh's scale).
    const double kappa = std::abs(t.dot(here.curvature * t));
    const double h = std::min({kappa > 0 ? std::sqrt(8 * tolerance / kappa) : 1.0, 1.0, until - traced});
    // Newton on (m . S = level, t . (S - point) = h).
    Eigen::Vector2d w = uv;
    bool converged = false;
    for (int it = 0; it < 16; ++it) {
      const auto q = surface.derivatives(w.x(), w.y());
      const Eigen::Vector2d f(m.dot(q.point) - level, t.dot(q.point - point) - h);
      if (f.norm() < 1e-11) {
        converged = true;
        break;
      }
      Eigen::Matrix2d j;
      j << m.dot(q.du), m.dot(q.dv), t.dot(q.du), t.dot(q.dv);
      const Eigen::Vector2d step = j.fullPivLu().solve(f);
      if (!step.allFinite()) break;
      w -= step;
    }
    // Stop where the trace is lost, or has wandered far off the patch (its extension is meant for a tool's width, not more).
    const bool far_off = w.x() < surface.u_min() - 0.25 * span_u || w.x() > surface.u_max() + 0.25 * span_u || w.y() < surface.v_min() - 0.25 * span_v ||
                         w.y() > surface.v_max() + 0.25 * span_v;
    if (!converged || far_off) break;
    SurfaceContact next;
    try {
      next = contact(surface, w.x(), w.y(), here.normal);
    } catch (const std::domain_error&) {
      break;
    }
    if (next.normal.dot(axis) < 0.1) break;
    traced += (next.point - point).norm();
    direction = next.point - point;
    point = next.point;
    reference = next.normal;
    uv = w;
    out.push_back(next);
  }
  return out;
}

}  // namespace drom::paths
