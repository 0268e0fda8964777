#include "paths/finish/parallel_planes.hpp"
#include "paths/cutter/stepover.hpp"

#include "paths/finish/exact_passes.hpp"
#include "paths/finish/swept_profile.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <numeric>

namespace drom::paths {

double target_scallop(const PassSettings& s) {
  return s.exact && s.stepover == StepoverModel::curved ? s.scallop - s.chord_tolerance : s.scallop;
}

ContactStep contact_step(const Eigen::Vector3d& n, const Eigen::Matrix3d& curvature, const PassSettings& s) {
  ContactStep c;
  const Eigen::Vector3d& a = s.axis;
  const Eigen::Vector3d m = a.cross(s.feed).normalized();
  c.slope = std::acos(std::clamp(n.dot(a), -1.0, 1.0));
  Eigen::Vector3d along = m.cross(n);  // the pass's tangent: in the plane and in the tangent plane
  if (along.norm() < 1e-12) along = s.feed;  // the tangent plane contains the plane's normal: a wall along the pass
  along.normalize();
  const Eigen::Vector3d uphill = a - a.dot(n) * n;
  c.alpha = uphill.norm() > 1e-12 ? std::acos(std::min(1.0, std::abs(along.dot(uphill.normalized())))) : 0.0;
  c.effective_radius = effective_radius(s.tool, c.slope, c.alpha);
  Eigen::Vector3d across = n.cross(along);
  if (m.dot(across) < 0) across = -across;  // towards the next plane
  c.curvature = across.dot(curvature * across);
  const double scallop = target_scallop(s);
  double step = s.stepover == StepoverModel::curved ? curved_stepover(scallop, c.effective_radius, c.curvature) : flat_stepover(s.scallop, c.effective_radius);
  if (s.stepover == StepoverModel::curved && s.tool.kind == ToolKind::torus && step > 0) {
    // The torus's swept profile instead of eq. 1.5's circle on level ground (the sum of its two
    // sides' reaches), bent by the ground as eq. 1.5's circle would be.
    const SweptProfileTable& table = s.profile ? *s.profile : swept_profile_table(s.tool, scallop);
    const Eigen::Vector3d feed = (s.feed - s.feed.dot(a) * a).normalized();
    const SideReach reach = table.reach(c.slope, std::atan2(n.dot(m), n.dot(feed)));
    const double level_ground = flat_stepover(scallop, c.effective_radius);
    if (std::isfinite(level_ground) && level_ground > 0) step *= (reach.minus + reach.plus) / level_ground;
    else step = reach.minus + reach.plus;
  }
  c.stepover = std::min(step, level_ground_stepover(s.tool, s.scallop));
  // The plane step that moves the contact `stepover` along the surface: an arc w from p ends at
  // p + w t + (w^2 / 2) kappa n, so the step is w (m . t) + (w^2 / 2) kappa (m . n). The seed keeps
  // the first term only.
  const double w = c.stepover;
  c.spacing = w * m.dot(across);
  if (s.stepover != StepoverModel::seed) c.spacing = std::max(1e-3 * c.spacing, c.spacing + 0.5 * w * w * c.curvature * m.dot(n));
  return c;
}

namespace {

struct Crossing {
  int a, b;  // mesh nodes
  double t;  // point = a + t (b - a)
};

// Slices of one zone by planes of increasing level: marching squares over the zone's mesh cells,
// crossings chained through the mesh edges they share.
class ZoneSlicer {
 public:
  ZoneSlicer(const MachiningMesh& mesh, const std::vector<int>& cells, const Eigen::Vector3d& normal) : mesh_(mesh), cells_(cells) {
    phi_.resize(static_cast<std::size_t>(mesh.node_count()));
    for (int k = 0; k < mesh.node_count(); ++k) phi_[static_cast<std::size_t>(k)] = normal.dot(mesh.points[static_cast<std::size_t>(k)]);
    lo_.resize(cells.size());
    hi_.resize(cells.size());
    for (std::size_t k = 0; k < cells.size(); ++k) {
      const auto c = corners(cells[k]);
      lo_[k] = hi_[k] = phi(c[0]);
      for (int q = 1; q < 4; ++q) {
        lo_[k] = std::min(lo_[k], phi(c[static_cast<std::size_t>(q)]));
        hi_[k] = std::max(hi_[k], phi(c[static_cast<std::size_t>(q)]));
      }
    }
    in_zone_.assign(static_cast<std::size_t>(mesh.cell_count()), 0);
    for (const int c : cells) in_zone_[static_cast<std::size_t>(c)] = 1;
    order_.resize(cells.size());
    std::iota(order_.begin(), order_.end(), 0);
    std::sort(order_.begin(), order_.end(), [&](int x, int y) { return lo_[static_cast<std::size_t>(x)] < lo_[static_cast<std::size_t>(y)]; });
    const int edges = mesh.cells_u * (mesh.cells_v + 1) + (mesh.cells_u + 1) * mesh.cells_v;
    edge_stamp_.assign(static_cast<std::size_t>(edges), -1);
    edge_segments_.resize(static_cast<std::size_t>(edges));
    edge_crossing_.resize(static_cast<std::size_t>(edges));
  }

  bool holds(int cell) const { return in_zone_[static_cast<std::size_t>(cell)] != 0; }

  double min_level() const { return lo_.empty() ? 0 : *std::min_element(lo_.begin(), lo_.end()); }
  double max_level() const { return hi_.empty() ? 0 : *std::max_element(hi_.begin(), hi_.end()); }

  // Cells entirely below `level` are never needed again.
  void accept(double level) {
    std::erase_if(active_, [&](int k) { return hi_[static_cast<std::size_t>(k)] < level; });
  }

  // The connected crossings at `level` (>= every accepted level), each chain in mesh order.
  std::vector<std::vector<Crossing>> slice(double level) {
    while (next_ < order_.size() && lo_[static_cast<std::size_t>(order_[next_])] <= level) active_.push_back(order_[next_++]);
    ++stamp_;
    segments_.clear();
    for (const int k : active_) {
      if (!(lo_[static_cast<std::size_t>(k)] < level && level <= hi_[static_cast<std::size_t>(k)])) continue;
      cell_segments(cells_[static_cast<std::size_t>(k)], level);
    }
    return chains();
  }

 private:
  std::array<int, 4> corners(int cell) const {
    const int i = cell / mesh_.cells_v, j = cell % mesh_.cells_v;
    return {mesh_.node(i, j), mesh_.node(i + 1, j), mesh_.node(i + 1, j + 1), mesh_.node(i, j + 1)};
  }
  double phi(int node) const { return phi_[static_cast<std::size_t>(node)]; }

  // Edges of cell (i, j): 0 (n0 n1), 1 (n1 n2), 2 (n3 n2), 3 (n0 n3).
  std::array<int, 4> edge_ids(int cell) const {
    const int i = cell / mesh_.cells_v, j = cell % mesh_.cells_v, along_u = mesh_.cells_u * (mesh_.cells_v + 1);
    return {i * (mesh_.cells_v + 1) + j, along_u + (i + 1) * mesh_.cells_v + j, i * (mesh_.cells_v + 1) + j + 1, along_u + i * mesh_.cells_v + j};
  }

  void cell_segments(int cell, double level) {
    const auto n = corners(cell);
    const auto e = edge_ids(cell);
    static constexpr int ends[4][2] = {{0, 1}, {1, 2}, {3, 2}, {0, 3}};
    std::array<bool, 4> above;
    for (int q = 0; q < 4; ++q) above[static_cast<std::size_t>(q)] = phi(n[static_cast<std::size_t>(q)]) >= level;
    std::array<int, 4> crossed{};
    int count = 0;
    for (int q = 0; q < 4; ++q) {
      const int a = n[static_cast<std::size_t>(ends[q][0])], b = n[static_cast<std::size_t>(ends[q][1])];
      if ((phi(a) >= level) == (phi(b) >= level)) continue;
      const int id = e[static_cast<std::size_t>(q)];
      if (edge_stamp_[static_cast<std::size_t>(id)] != stamp_) {
        edge_stamp_[static_cast<std::size_t>(id)] = stamp_;
        edge_segments_[static_cast<std::size_t>(id)] = {-1, -1};
        edge_crossing_[static_cast<std::size_t>(id)] = {a, b, (level - phi(a)) / (phi(b) - phi(a))};
      }
      crossed[static_cast<std::size_t>(count++)] = q;
    }
    if (count == 2) {
      add_segment(e[static_cast<std::size_t>(crossed[0])], e[static_cast<std::size_t>(crossed[1])]);
    } else if (count == 4) {
      // A saddle: the centre's side decides which corners the level cuts off.
      const double centre = 0.25 * (phi(n[0]) + phi(n[1]) + phi(n[2]) + phi(n[3]));
      if ((centre >= level) == above[0]) {
        add_segment(e[0], e[1]);
        add_segment(e[2], e[3]);
      } else {
        add_segment(e[3], e[0]);
        add_segment(e[1], e[2]);
      }
    }
  }

  void add_segment(int e0, int e1) {
    const int s = static_cast<int>(segments_.size());
    segments_.push_back({e0, e1});
    for (const int e : {e0, e1}) {
      auto& slots = edge_segments_[static_cast<std::size_t>(e)];
      (slots[0] < 0 ? slots[0] : slots[1]) = s;
    }
  }

  int other_segment(int edge, int segment) const {
    const auto& slots = edge_segments_[static_cast<std::size_t>(edge)];
    return slots[0] == segment ? slots[1] : slots[0];
  }

  std::vector<std::vector<Crossing>> chains() {
    std::vector<std::vector<Crossing>> result;
    visited_.assign(segments_.size(), false);
    for (std::size_t s0 = 0; s0 < segments_.size(); ++s0) {
      if (visited_[s0]) continue;
      // Walk back to an open end (or around a closed loop), then forward collecting edges.
      int seg = static_cast<int>(s0), entry = segments_[s0][1];
      for (std::size_t guard = 0; guard <= segments_.size(); ++guard) {
        const int exit = segments_[static_cast<std::size_t>(seg)][0] == entry ? segments_[static_cast<std::size_t>(seg)][1] : segments_[static_cast<std::size_t>(seg)][0];
        const int prev = other_segment(exit, seg);
        if (prev < 0 || prev == static_cast<int>(s0)) {
          entry = exit;
          break;
        }
        entry = exit;
        seg = prev;
      }
      // `entry` is the open end of `seg` (or where a loop closes).
      std::vector<Crossing> chain;
      chain.push_back(edge_crossing_[static_cast<std::size_t>(entry)]);
      int edge = entry;
      while (seg >= 0 && !visited_[static_cast<std::size_t>(seg)]) {
        visited_[static_cast<std::size_t>(seg)] = true;
        const auto& sg = segments_[static_cast<std::size_t>(seg)];
        edge = sg[0] == edge ? sg[1] : sg[0];
        chain.push_back(edge_crossing_[static_cast<std::size_t>(edge)]);
        seg = other_segment(edge, seg);
      }
      result.push_back(std::move(chain));
    }
    return result;
  }

  const MachiningMesh& mesh_;
  const std::vector<int>& cells_;
  std::vector<double> phi_, lo_, hi_;
  std::vector<int> order_, active_;
  std::size_t next_ = 0;
  int stamp_ = 0;
  std::vector<int> edge_stamp_;
  std::vector<std::array<int, 2>> edge_segments_;
  std::vector<Crossing> edge_crossing_;
  std::vector<std::array<int, 2>> segments_;
  std::vector<bool> visited_;
  std::vector<char> in_zone_;
};

// A crossing of the mesh's edge (a, b) as a point of the iso-line it lies on: its parameters, and
// the free parameter's range along that edge.
IsoCrossing iso_crossing(const MachiningMesh& mesh, const Crossing& x) {
  const int row = mesh.cells_v + 1, ia = x.a / row, ja = x.a % row, ib = x.b / row, jb = x.b % row;
  IsoCrossing c;
  c.along_u = ja == jb;
  const double ua = mesh.node_u(ia), ub = mesh.node_u(ib), va = mesh.node_v(ja), vb = mesh.node_v(jb);
  c.u = ua + x.t * (ub - ua);
  c.v = va + x.t * (vb - va);
  c.lo = c.along_u ? std::min(ua, ub) : std::min(va, vb);
  c.hi = c.along_u ? std::max(ua, ub) : std::max(va, vb);
  return c;
}

// One plane's passes, with the step each contact point allows. With `reach_side` (-1 or +1), also
// how far towards that side (plane units) each pass alone keeps the bound: for the zone's first and
// last planes.
std::vector<PlanePass> passes_at(ZoneSlicer& slicer, const MachiningMesh& mesh, double level, const PassSettings& s, int reach_side = 0) {
  std::vector<PlanePass> passes;
  for (const auto& chain : slicer.slice(level)) {
    PlanePass p;
    p.level = level;
    std::vector<Eigen::Matrix3d> curvatures;
    for (const auto& x : chain) {
      const auto A = static_cast<std::size_t>(x.a), B = static_cast<std::size_t>(x.b);
      p.cc.push_back(mesh.points[A] + x.t * (mesh.points[B] - mesh.points[A]));
      p.normals.push_back((mesh.normals[A] + x.t * (mesh.normals[B] - mesh.normals[A])).normalized());
      curvatures.push_back(mesh.curvature[A] + x.t * (mesh.curvature[B] - mesh.curvature[A]));
    }
    if (s.exact) {
      // The same crossings solved on the true iso-curves, then refined along the true intersection.
      std::vector<IsoCrossing> iso;
      for (const auto& x : chain) iso.push_back(iso_crossing(mesh, x));
      // Half the tolerance on the contact curve: the tool-tip curve, offset from it, bends up to a
      // few times more sharply where the ground is concave.
      const auto contacts = exact_chain(*mesh.surface, s.axis.cross(s.feed).normalized(), level, iso, p.normals, 0.5 * s.chord_tolerance);
      p.cc.clear();
      p.normals.clear();
      curvatures.clear();
      for (const auto& c : contacts) {
        p.cc.push_back(c.point);
        p.normals.push_back(c.normal);
        curvatures.push_back(c.curvature);
      }
    }
    // The parameters of the chain's ends, where a run-out starts.
    const auto end_uv = [&](const Crossing& x) {
      const IsoCrossing c = iso_crossing(mesh, x);
      return Eigen::Vector2d(c.u, c.v);
    };
    Eigen::Vector2d uv_front = end_uv(chain.front()), uv_back = end_uv(chain.back());
    if ((p.cc.back() - p.cc.front()).dot(s.feed) < 0) {
      std::reverse(p.cc.begin(), p.cc.end());
      std::reverse(p.normals.begin(), p.normals.end());
      std::reverse(curvatures.begin(), curvatures.end());
      std::swap(uv_front, uv_back);
    }
    p.worst_stepover = p.spacing = p.worst_effective_radius = std::numeric_limits<double>::infinity();
    for (std::size_t i = 0; i < p.cc.size(); ++i) {
      const ContactStep step = contact_step(p.normals[i], curvatures[i], s);
      if (s.stepover == StepoverModel::curved && !(step.stepover > 0) && p.gouging_contacts++ == 0) p.first_gouge = p.cc[i];
      p.worst_stepover = std::min(p.worst_stepover, step.stepover);
      if (s.stepover != StepoverModel::seed) p.spacing = std::min(p.spacing, step.spacing);
      else if (step.effective_radius < p.worst_effective_radius * (1 - 1e-12)) p.spacing = step.spacing;  // ties: the first along the feed
      p.worst_effective_radius = std::min(p.worst_effective_radius, step.effective_radius);
    }
    if (reach_side != 0) {
      const Eigen::Vector3d m = s.axis.cross(s.feed).normalized();
      // At most about 16 points of a probe pass: a torus's reach costs some 0.1 ms, and a probe
      // along an edge parallel to the planes spans the whole edge.
      const std::size_t stride = std::max<std::size_t>(1, p.cc.size() / 16);
      for (std::size_t i = 0; i < p.cc.size(); i += stride) {
        const Eigen::Vector3d& n = p.normals[i];
        const Eigen::Vector3d along = i + 1 < p.cc.size() ? Eigen::Vector3d(p.cc[i + 1] - p.cc[i]) : Eigen::Vector3d(p.cc[i] - p.cc[i - 1]);
        Eigen::Vector3d across = n.cross(along).normalized();
        if (reach_side * m.dot(across) < 0) across = -across;
        if (!across.allFinite() || along.norm() == 0) continue;
        const double kappa = across.dot(curvatures[i] * across);
        const double y = one_pass_reach(s.tool, n, s.axis, along.normalized(), across, kappa, target_scallop(s));
        if (!std::isfinite(y)) continue;
        p.reach = std::min(p.reach, std::max(1e-3 * y, y * std::abs(m.dot(across)) + reach_side * 0.5 * y * y * kappa * m.dot(n)));
      }
    }
    // A closed loop has no end to run out of.
    p.open = p.cc.size() >= 2 && (chain.front().a != chain.back().a || chain.front().b != chain.back().b);
    p.uv_front = uv_front;
    p.uv_back = uv_back;
    passes.push_back(std::move(p));
  }
  std::sort(passes.begin(), passes.end(), [&](const PlanePass& x, const PlanePass& y) { return x.cc.front().dot(s.feed) < y.cc.front().dot(s.feed); });
  return passes;
}

// The pass run on past both its ends (PassSettings::run_out), once its plane is placed: the step
// keeps the bound inside the zone, and also over the first `margin` of each run-out, where the tool
// cuts the edge's material from.
void add_run_outs(PlanePass& p, const ZoneSlicer& slicer, const MachiningMesh& mesh, const PassSettings& s) {
  if (!(s.run_out > 0) || !p.open || !mesh.surface) return;
  const double level = p.level;
  const Eigen::Vector3d m = s.axis.cross(s.feed).normalized();
  const double tolerance = s.exact ? 0.5 * s.chord_tolerance : s.chord_tolerance;
  // On past the run-out while the zone still lies beside the pass, within a plane step either
  // side (an edge met obliquely): the neighbouring passes' material there needs this one too.
  const geometry::NurbsSurface& surface = *mesh.surface;
  const double plane_step = std::isfinite(p.spacing) ? p.spacing : p.worst_stepover;
  // Once the trace has left the zone and comes back into it, it is on another pass of the same
  // plane (a zone crossed twice): no further than the margin along that one.
  bool left = false, back_in = false;
  const auto zone_beside = [&](const TracePoint& q) {
    const Eigen::Vector3d across = q.normal.cross(q.tangent).normalized();
    Eigen::Matrix<double, 3, 2> j;
    j << q.derivatives.du, q.derivatives.dv;
    const auto metric = (j.transpose() * j).eval().ldlt();
    const double w = plane_step / std::max(0.2, std::abs(m.dot(across)));
    const auto in_zone = [&](double f) {
      const Eigen::Vector2d at = q.uv + metric.solve(j.transpose() * (f * w * across));
      const double fu = (at.x() - surface.u_min()) / (surface.u_max() - surface.u_min()), fv = (at.y() - surface.v_min()) / (surface.v_max() - surface.v_min());
      return fu >= 0 && fu < 1 && fv >= 0 && fv < 1 && slicer.holds(mesh.cell(static_cast<int>(fu * mesh.cells_u), static_cast<int>(fv * mesh.cells_v)));
    };
    const bool here = in_zone(0);
    if (!here) left = true;
    else if (left) back_in = true;
    if (back_in) return false;
    if (here) return true;
    for (const double f : {-1.0, -0.5, 0.5, 1.0})
      if (in_zone(f)) return true;
    return false;
  };
  // On past the last place the zone lies beside by a step (the probes are half a step apart)
  // and by R - r: a torus tilted on the ground cuts the material beside its contact with a part
  // of its ring up to R - r ahead of or behind the contact (a ball: at the contact).
  const double ring = s.tool.kind == ToolKind::ball ? 0.0 : s.tool.radius - s.tool.corner_radius;
  const double margin = std::min(s.run_out, std::max(0.5, plane_step) + ring);
  // The direction a pass leaves by: from the last point apart from its end (a chain can repeat a point).
  const auto leaving = [&](bool at_back) {
    const std::size_t count = p.cc.size();
    const Eigen::Vector3d& end = at_back ? p.cc.back() : p.cc.front();
    for (std::size_t k = 1; k < count; ++k) {
      const Eigen::Vector3d d = end - (at_back ? p.cc[count - 1 - k] : p.cc[k]);
      if (d.norm() > 1e-9) return d;
    }
    return Eigen::Vector3d(Eigen::Vector3d::Zero());
  };
  const TraceRules rules{.plane_normal = m, .level = level, .axis = s.axis, .margin = margin, .max_length = s.run_out, .chord_tolerance = tolerance, .needed = zone_beside};
  const auto back = trace_on(surface, {.uv = p.uv_back, .point = p.cc.back(), .direction = leaving(true), .reference_normal = p.normals.back()}, rules);
  left = back_in = false;
  const auto front = trace_on(surface, {.uv = p.uv_front, .point = p.cc.front(), .direction = leaving(false), .reference_normal = p.normals.front()}, rules);
  // The tool cuts the material at the edge from up to `margin` past it: the step must keep the
  // bound there too.
  const auto splice = [&](const std::vector<SurfaceContact>& run, Eigen::Vector3d last, bool at_back) {
    std::vector<Eigen::Vector3d> points, normals;
    double along = 0;
    for (const auto& c : run) {
      along += (c.point - last).norm();
      last = c.point;
      points.push_back(c.point);
      normals.push_back(c.normal);
      if (along <= margin) {
        const ContactStep step = contact_step(c.normal, c.curvature, s);
        p.worst_stepover = std::min(p.worst_stepover, step.stepover);
        if (s.stepover != StepoverModel::seed) p.spacing = std::min(p.spacing, step.spacing);
      }
    }
    p.run_out_length += along;
    if (at_back) {
      p.cc.insert(p.cc.end(), points.begin(), points.end());
      p.normals.insert(p.normals.end(), normals.begin(), normals.end());
    } else {
      p.cc.insert(p.cc.begin(), points.rbegin(), points.rend());
      p.normals.insert(p.normals.begin(), normals.rbegin(), normals.rend());
    }
  };
  splice(back, p.cc.back(), true);
  splice(front, p.cc.front(), false);
}

double plane_spacing(const std::vector<PlanePass>& plane) {
  double spacing = std::numeric_limits<double>::infinity();
  for (const auto& p : plane) spacing = std::min(spacing, p.spacing);
  return spacing;
}

}  // namespace

std::vector<PlanePass> plan_passes(const MachiningMesh& mesh, const std::vector<int>& cells, const PassSettings& settings) {
  std::vector<PlanePass> result;
  if (cells.empty()) return result;
  PassSettings s = settings;
  if (s.stepover == StepoverModel::curved && s.tool.kind == ToolKind::torus && !s.profile)
    s.profile = &swept_profile_table(s.tool, target_scallop(s));
  const Eigen::Vector3d normal = s.axis.cross(s.feed).normalized();
  ZoneSlicer slicer(mesh, cells, normal);
  const double lo = slicer.min_level(), hi = slicer.max_level(), extent = hi - lo;
  // A floor on the plane step, so a point where no step keeps the bound (the tool gouges) cannot stall the planner.
  // (5 % of the corner's step: a zone the tool gouges all over would otherwise be planned in tens
  // of thousands of planes; the seed's model keeps its own floor, which its tables were matched with.)
  const double min_spacing = (s.stepover == StepoverModel::seed ? 1e-3 : 0.05) * flat_stepover(s.scallop, s.tool.corner_radius);
  const auto spacing_of = [&](const std::vector<PlanePass>& plane) { return std::max(min_spacing, plane_spacing(plane)); };
  // The first plane half a step inside the zone, the step measured just inside its edge.
  std::vector<PlanePass> probe = passes_at(slicer, mesh, lo + std::min(1e-3, 0.5 * extent), s, s.stepover == StepoverModel::seed ? 0 : -1);
  double first_reach = probe.empty() ? 0.5 * extent : 0.5 * spacing_of(probe);
  if (s.stepover != StepoverModel::seed)
    for (const auto& p : probe) first_reach = std::min(first_reach, p.reach);
  double level = std::min(lo + std::max(first_reach, 0.5 * min_spacing), lo + 0.5 * extent);
  // The step the far edge allows, measured just inside it the same way (its own slicer: slicing
  // near the top first would make every later slice walk every cell).
  double last_reach = std::numeric_limits<double>::infinity();
  if (s.stepover != StepoverModel::seed) {
    ZoneSlicer far_slicer(mesh, cells, normal);
    for (const auto& p : passes_at(far_slicer, mesh, hi - std::min(1e-3, 0.5 * extent), s, +1)) last_reach = std::min(last_reach, p.reach);
  }
  std::vector<PlanePass> plane = passes_at(slicer, mesh, level, s);
  int index = 0;
  while (true) {
    slicer.accept(level);
    for (auto& p : plane) add_run_outs(p, slicer, mesh, s);
    double spacing = spacing_of(plane);
    for (auto& p : plane) {
      p.plane = index;
      const bool backwards = s.zigzag && index % 2 == 1;
      if (backwards) {
        std::reverse(p.cc.begin(), p.cc.end());
        std::reverse(p.normals.begin(), p.normals.end());
      }
    }
    if (s.zigzag && index % 2 == 1) std::reverse(plane.begin(), plane.end());
    for (auto& p : plane) result.push_back(std::move(p));
    ++index;
    double next = level + spacing;
    if (s.stepover == StepoverModel::seed) {
      if (next >= hi) break;
      plane = passes_at(slicer, mesh, next, s);
    } else {
      // The last plane: within half a step of the far edge, the step the edge itself allows.
      const double reach = std::max(0.5 * min_spacing, std::min(0.5 * spacing, last_reach));
      // (level = hi - reach need not give level + reach >= hi in floating point: the tolerance
      // ends the zone there instead of planning that plane forever.)
      if (!(level + reach < hi - 1e-9 * (1 + std::abs(hi)))) break;
      next = std::min(next, hi - reach);
      plane = passes_at(slicer, mesh, next, s);
      // The scallop between two passes depends on both: where the next pass allows a smaller step,
      // its plane moves back (twice at most; the step barely changes over a fraction of a step).
      for (int retry = 0; retry < 2 && !plane.empty(); ++retry) {
        const double allowed = spacing_of(plane);
        if (next - level <= allowed * (1 + 1e-9)) break;
        next = level + allowed;
        plane = passes_at(slicer, mesh, next, s);
      }
    }
    if (!(next > level)) break;  // no progress (a NaN step included): never plan a plane twice
    level = next;
    if (plane.empty()) break;
  }
  return result;
}

}  // namespace drom::paths
