#include "paths/orient/orient_scene.hpp"

#include "geometry/local_geometry.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <functional>
#include <numbers>
#include <stdexcept>

namespace drom::paths {

namespace {

using Shape = std::function<Eigen::Vector3d(double u, double v)>;

// A cubic B-spline patch whose control points sit on the shape on a uniform count_u x count_v grid:
// the generated CAD (smooth, close to the shape, exactly a B-spline).
geometry::NurbsSurface bspline_on(const Shape& shape, int count_u, int count_v) {
  std::vector<Eigen::Vector3d> net;
  for (int i = 0; i < count_u; ++i)
    for (int j = 0; j < count_v; ++j) net.push_back(shape(static_cast<double>(i) / (count_u - 1), static_cast<double>(j) / (count_v - 1)));
  const int du = std::min(3, count_u - 1), dv = std::min(3, count_v - 1);
  return geometry::NurbsSurface(du, dv, geometry::NurbsSurface::clamped_uniform_knots(du, count_u), geometry::NurbsSurface::clamped_uniform_knots(dv, count_v),
                                count_u, count_v, std::move(net));
}

// A flat quadrilateral patch; its outward normal is (b − a) × (c − a) for corners a (0,0), b (1,0), c (0,1).
geometry::NurbsSurface quad(const Eigen::Vector3d& a, const Eigen::Vector3d& b, const Eigen::Vector3d& c, const Eigen::Vector3d& d) {
  // Control point (i, j) at index i * 2 + j: (0,0) a, (0,1) c, (1,0) b, (1,1) d.
  return geometry::NurbsSurface::bezier(2, 2, {a, c, b, d});
}

// Whether the patch's S_u × S_v (at its centre) points against `outward`.
bool needs_flip(const geometry::NurbsSurface& s, const Eigen::Vector3d& outward) {
  const auto d = s.derivatives(0.5 * (s.u_min() + s.u_max()), 0.5 * (s.v_min() + s.v_max()));
  return d.du.cross(d.dv).dot(outward) < 0;
}

std::vector<Eigen::Vector3d> polyline(const std::vector<Eigen::Vector3d>& corners, double step) {
  std::vector<Eigen::Vector3d> out{corners.front()};
  for (std::size_t k = 1; k < corners.size(); ++k) {
    const int n = std::max(1, static_cast<int>(std::ceil((corners[k] - corners[k - 1]).norm() / step)));
    for (int i = 1; i <= n; ++i) out.push_back(corners[k - 1] + (corners[k] - corners[k - 1]) * (static_cast<double>(i) / n));
  }
  return out;
}

ToolAssembly ball_tool(double radius, double flute, double shank, double stick_out, double holder_radius, double holder_length) {
  ToolAssembly t;
  t.cutter = {ToolKind::ball, radius, radius};
  t.flute_length = flute;
  t.shank_radius = shank;
  t.gauge_length = stick_out;
  t.holder.z = {0, holder_length};
  t.holder.radius = {holder_radius, holder_radius};
  return t;
}

}  // namespace

ObstacleCloud scene_obstacles(const OrientScene& scene, double spacing, double cell) {
  ObstacleCloud all({}, {}, cell);
  for (const auto& p : scene.check_patches) all.append(ObstacleCloud::from_patch(p.surface, spacing, p.flip, cell));
  if (!scene.check_mesh.triangles.empty()) all.append(ObstacleCloud::from_triangles(scene.check_mesh, spacing, cell));
  return all;
}

TriangleSoup scene_check_triangles(const OrientScene& scene, double step) {
  TriangleSoup soup = scene.check_mesh;
  for (const auto& p : scene.check_patches) soup.append(triangulate_patch(p.surface, step, p.flip));
  return soup;
}

FramedPath iso_pass(const geometry::NurbsSurface& surface, bool flip, double v, double u0, double u1, int count, double pivot_offset, double roll,
                    double pitch, double lead_in) {
  std::vector<Eigen::Vector3d> cl, normals;
  for (int i = 0; i < count; ++i) {
    const double u = u0 + (u1 - u0) * i / (count - 1);
    const geometry::LocalGeometry g = geometry::local_geometry(surface.derivatives(u, v));
    const Eigen::Vector3d n = flip ? Eigen::Vector3d(-g.normal) : g.normal;
    cl.push_back(g.point + pivot_offset * n);
    normals.push_back(n);
  }
  if (lead_in > 0) {
    const Eigen::Vector3d back = (cl[0] - cl[1]).normalized();
    const double step = (cl[1] - cl[0]).norm();
    const int extra = static_cast<int>(std::ceil(lead_in / step));
    for (int i = 1; i <= extra; ++i) {
      cl.insert(cl.begin(), cl.front() + step * back);
      normals.insert(normals.begin(), normals.front());
    }
  }
  return FramedPath::from_points(cl, normals, roll, pitch);
}

ToolAssembly default_tool(const BumpOptions&) { return ball_tool(5, 15, 5, 40, 16, 40); }
ToolAssembly default_tool(const CornerOptions& o) { return ball_tool(3, 8, 3, o.stick_out, 8, 35); }
ToolAssembly default_tool(const ImpellerOptions&) { return ball_tool(5, 15, 5, 45, 12, 40); }
ToolAssembly default_tool(const PanelOptions&) { return ball_tool(5, 15, 5, 40, 16, 40); }

OrientScene bump_scene(const BumpOptions& o) {
  // Table 4.5 (mm): i = 0..4 along u, j = 0..2 along v; control point (i, j) at index i * 3 + j.
  const double table[3][5][3] = {{{0, 0, 0}, {10, 0, 0}, {20, 0, 0}, {35, 0, 0}, {50, 0, 0}},
                                 {{10, -10, 10}, {15, 0, 10}, {25, 10, 10}, {38, 0, 10}, {50, -10, 10}},
                                 {{0, -10, 25}, {10, 0, 25}, {20, 10, 25}, {35, 20, 25}, {50, -10, 25}}};
  std::vector<Eigen::Vector3d> net;
  for (int i = 0; i < 5; ++i)
    for (int j = 0; j < 3; ++j) net.emplace_back(table[j][i][0], table[j][i][1], table[j][i][2]);
  OrientScene s;
  s.name = "bump";
  s.description = "the seed's Bézier bump (Table 4.5) beside a straight pass along x at y = " + std::to_string(o.lateral) + " mm";
  const geometry::NurbsSurface bump = geometry::NurbsSurface::bezier(5, 3, net);
  s.check_patches.push_back({"bump", bump, needs_flip(bump, Eigen::Vector3d::UnitY())});
  s.part_surfaces.push_back({"floor", quad({-30, -30, 0}, {80, -30, 0}, {-30, 60, 0}, {80, 60, 0}), false});
  s.tool = o.tool ? *o.tool : default_tool(o);
  const double z = s.tool.cutter.pivot_height();
  s.passes.push_back(FramedPath::from_points(polyline({{-20, o.lateral, z}, {70, o.lateral, z}}, 0.5),
                                             std::vector<Eigen::Vector3d>(static_cast<std::size_t>(181), Eigen::Vector3d::UnitZ()), 0, 0));
  s.pass_names.push_back("y = " + std::to_string(o.lateral));
  return s;
}

OrientScene corner_scene(const CornerOptions& o) {
  OrientScene s;
  s.name = "corner";
  s.description = "a 90° pocket corner: walls 10 mm (first leg) and 14 mm (second leg) from the CL path, 24 mm high; tool stick-out " +
                  std::to_string(o.stick_out) + " mm";
  const double w1 = 10, w2 = 14, h = 24, xc = 60;
  // Wall 1 (y = w1) faces −y; wall 2 (x = xc + w2) faces −x. Both start below the floor so the corner is closed.
  s.check_patches.push_back({"wall 1", quad({15, w1, -2}, {xc + w2, w1, -2}, {15, w1, h}, {xc + w2, w1, h}), false});
  s.check_patches.back().flip = needs_flip(s.check_patches.back().surface, -Eigen::Vector3d::UnitY());
  s.check_patches.push_back({"wall 2", quad({xc + w2, -45, -2}, {xc + w2, w1, -2}, {xc + w2, -45, h}, {xc + w2, w1, h}), false});
  s.check_patches.back().flip = needs_flip(s.check_patches.back().surface, -Eigen::Vector3d::UnitX());
  s.part_surfaces.push_back({"floor", quad({-10, -80, 0}, {xc + w2, -80, 0}, {-10, w1, 0}, {xc + w2, w1, 0}), false});
  s.tool = o.tool ? *o.tool : default_tool(o);
  const double z = s.tool.cutter.pivot_height();
  const auto cl = polyline({{0, 0, z}, {xc, 0, z}, {xc, -80, z}}, 0.5);
  s.passes.push_back(FramedPath::from_points(cl, std::vector<Eigen::Vector3d>(cl.size(), Eigen::Vector3d::UnitZ()), o.roll, 0));
  s.pass_names.push_back("corner");
  return s;
}

namespace {
struct ImpellerShape {
  const ImpellerOptions& o;
  double radius(double u) const { return o.hub_inlet_radius + (o.hub_outlet_radius - o.hub_inlet_radius) * u; }
  double hub_z(double u) const { return o.hub_inlet_height * (1 - u) * (1 - u); }
  double height(double u) const { return o.blade_height_inlet + (o.blade_height_outlet - o.blade_height_inlet) * u; }
  double pitch() const { return 2 * std::numbers::pi / o.blades; }
  // Blade k's camber angle at (u, w), w in [0, 1] from the hub to the tip: wrapped, and leaning.
  double camber(int k, double u, double w) const { return pitch() * k + o.wrap * u + w * height(u) * std::tan(o.lean) / radius(u); }
  Eigen::Vector3d at(double r, double theta, double z) const { return {r * std::cos(theta), r * std::sin(theta), z}; }
};
}  // namespace

geometry::NurbsSurface impeller_hub_patch(const ImpellerOptions& o, int vein) {
  const ImpellerShape sh{o};
  return bspline_on(
      [&](double u, double v) {
        const double r = sh.radius(u), half = 0.5 * o.thickness / r;
        const double a = sh.camber(vein, u, 0) + half, b = sh.camber(vein + 1, u, 0) - half;
        return sh.at(r, a + (b - a) * v, sh.hub_z(u));
      },
      14, 6);
}

geometry::NurbsSurface impeller_blade_side(const ImpellerOptions& o, int blade, int side) {
  const ImpellerShape sh{o};
  // From slightly under the hub (so the root leaves no gap) to the tip.
  return bspline_on(
      [&](double u, double w) {
        const double r = sh.radius(u), ww = -0.05 + 1.05 * w;
        const double theta = sh.camber(blade, u, ww) + (side == 0 ? -1 : 1) * 0.5 * o.thickness / r;
        return sh.at(r, theta, sh.hub_z(u) + ww * sh.height(u));
      },
      14, 5);
}

namespace {
// CL points along the iso-line v of a hub patch at about `spacing` (its arc length on 64 chords), as a
// double so that a hostile spacing is counted, not overflowed.
double iso_line_points(const geometry::NurbsSurface& hub, double v, double spacing) {
  double length = 0;
  Eigen::Vector3d prev = hub.point(0, v);
  for (int i = 1; i <= 64; ++i) {
    const Eigen::Vector3d q = hub.point(i / 64.0, v);
    length += (q - prev).norm();
    prev = q;
  }
  return std::max(2.0, std::ceil(length / spacing) + 1);
}
}  // namespace

std::size_t impeller_passes_per_vein(const ImpellerOptions& o) {
  return static_cast<std::size_t>(std::llround(std::max(0.0, o.v_last - o.v_first) / o.v_step)) + 1;
}

double impeller_cl_points(const ImpellerOptions& o) {
  const geometry::NurbsSurface hub = impeller_hub_patch(o, 0);
  const std::size_t passes = impeller_passes_per_vein(o);
  double per_vein = 0;
  for (std::size_t p = 0; p < passes; ++p) per_vein += iso_line_points(hub, o.v_first + static_cast<double>(p) * o.v_step, o.point_spacing);
  const int veins = o.veins < 0 ? o.blades : std::min(o.veins, o.blades);
  return per_vein * veins;
}

OrientScene impeller_scene(const ImpellerOptions& o) {
  if (o.blades < 2) throw std::invalid_argument("an impeller needs at least two blades");
  const ImpellerShape sh{o};
  OrientScene s;
  s.name = "impeller";
  s.description = std::to_string(o.blades) + "-blade parametric impeller: hub r " + std::to_string(o.hub_inlet_radius) + "-" +
                  std::to_string(o.hub_outlet_radius) + " mm, blades wrapped " + std::to_string(o.wrap) + " rad and leaning " + std::to_string(o.lean) + " rad";
  for (int k = 0; k < o.blades; ++k)
    for (int side = 0; side < 2; ++side) {
      geometry::NurbsSurface b = impeller_blade_side(o, k, side);
      // Outward: away from the camber, towards +θ on the suction side (1), −θ on the pressure side (0).
      const double u = 0.5, r = sh.radius(u), theta = sh.camber(k, u, 0.5);
      const Eigen::Vector3d tangential(-std::sin(theta), std::cos(theta), 0);
      const bool flip = needs_flip(b, side == 1 ? tangential : Eigen::Vector3d(-tangential));
      (void)r;
      s.check_patches.push_back({"blade " + std::to_string(k) + (side == 0 ? " pressure" : " suction"), std::move(b), flip});
    }
  s.tool = o.tool ? *o.tool : default_tool(o);
  const int veins = o.veins < 0 ? o.blades : std::min(o.veins, o.blades);
  const int passes = static_cast<int>(impeller_passes_per_vein(o));
  for (int k = 0; k < veins; ++k) {
    const geometry::NurbsSurface hub = impeller_hub_patch(o, k);
    const bool flip = needs_flip(hub, Eigen::Vector3d::UnitZ());
    s.part_surfaces.push_back({"hub vein " + std::to_string(k), hub, flip});
    for (int p = 0; p < passes; ++p) {
      const double v = o.v_first + p * o.v_step;
      const int count = static_cast<int>(iso_line_points(hub, v, o.point_spacing));
      s.passes.push_back(iso_pass(hub, flip, v, 0, 1, count, s.tool.cutter.pivot_height(), 0, o.lead, o.lead_in));
      s.pass_names.push_back("vein " + std::to_string(k) + " v = " + std::to_string(v));
    }
  }
  return s;
}

OrientScene panel_scene(const PanelOptions& o) {
  OrientScene s;
  s.name = "panel";
  s.description = "the curved panel (outer radius " + std::to_string(o.outer_radius) + " mm): its pocket floor finished in 5 axes between the pocket walls and two clamp jaws";
  const double cx = o.length / 2, inner = o.outer_radius - o.depth;
  const auto top_z = [&](double x) { return std::sqrt(o.outer_radius * o.outer_radius - (x - cx) * (x - cx)) - o.outer_radius + o.thickness; };
  const auto floor_z = [&](double x) { return std::sqrt(inner * inner - (x - cx) * (x - cx)) - o.outer_radius + o.thickness; };
  const double x0 = (o.length - o.pocket) / 2, x1 = x0 + o.pocket, y0 = (o.width - o.pocket) / 2, y1 = y0 + o.pocket;
  const geometry::NurbsSurface floor = bspline_on([&](double u, double v) {
    const double x = x0 + (x1 - x0) * u;
    return Eigen::Vector3d(x, y0 + (y1 - y0) * v, floor_z(x));
  }, 9, 2);
  s.part_surfaces.push_back({"pocket floor", floor, needs_flip(floor, Eigen::Vector3d::UnitZ())});
  // Pocket walls, facing into the pocket.
  auto wall_x = [&](double x, double sign) {
    geometry::NurbsSurface w = bspline_on([&](double u, double v) { return Eigen::Vector3d(x, y0 + (y1 - y0) * u, floor_z(x) - 1 + (top_z(x) - floor_z(x) + 1) * v); }, 2, 2);
    return CheckPatch{"pocket wall x = " + std::to_string(x), w, needs_flip(w, Eigen::Vector3d(sign, 0, 0))};
  };
  auto wall_y = [&](double y, double sign) {
    geometry::NurbsSurface w = bspline_on([&](double u, double v) {
      const double x = x0 + (x1 - x0) * u;
      return Eigen::Vector3d(x, y, floor_z(x) - 1 + (top_z(x) - floor_z(x) + 1) * v);
    }, 9, 2);
    return CheckPatch{"pocket wall y = " + std::to_string(y), w, needs_flip(w, Eigen::Vector3d(0, sign, 0))};
  };
  s.check_patches = {wall_x(x0, 1), wall_x(x1, -1), wall_y(y0, 1), wall_y(y1, -1)};
  // Clamp jaws over the faces x = 0 and x = length: their inner faces and tops.
  for (int side = 0; side < 2; ++side) {
    const double xi = side == 0 ? o.clamp_reach : o.length - o.clamp_reach, xo = side == 0 ? -20 : o.length + 20;
    const double zb = top_z(xi), zt = zb + o.clamp_height, sign = side == 0 ? 1 : -1;
    geometry::NurbsSurface face = quad({xi, -10, zb}, {xi, o.width + 10, zb}, {xi, -10, zt}, {xi, o.width + 10, zt});
    s.check_patches.push_back({"clamp " + std::to_string(side) + " face", face, needs_flip(face, Eigen::Vector3d(sign, 0, 0))});
    geometry::NurbsSurface top = quad({xi, -10, zt}, {xo, -10, zt}, {xi, o.width + 10, zt}, {xo, o.width + 10, zt});
    s.check_patches.push_back({"clamp " + std::to_string(side) + " top", top, needs_flip(top, Eigen::Vector3d::UnitZ())});
  }
  s.tool = o.tool ? *o.tool : default_tool(o);
  // Centred on C, its lowest edge (the bottom face at x = 0 and x = length) standing on the table.
  s.part_origin = Eigen::Vector3d(-o.length / 2, -o.width / 2, o.thickness - top_z(0));
  const bool flip = s.part_surfaces.front().flip;
  for (double y = y0 + s.tool.cutter.radius + 1; y <= y1 - s.tool.cutter.radius - 1 + 1e-9; y += o.stepover) {
    const double v = (y - y0) / (y1 - y0);
    s.passes.push_back(iso_pass(floor, flip, v, 0.02, 0.98, static_cast<int>(std::ceil(0.96 * o.pocket / 0.5)) + 1, s.tool.cutter.pivot_height(), 0, o.lead));
    s.pass_names.push_back("y = " + std::to_string(y));
  }
  return s;
}

}  // namespace drom::paths
