// Issue 29: volume-fraction removal is exact for plane cuts on element faces at any voxel size, on
// structured, graded and tetrahedral meshes, and converges for cuts inside elements.
#include "fem/mesh_geometry.hpp"
#include "fem/mesh.hpp"
#include "fem/structured_mesh.hpp"
#include "fem/tet_mesh.hpp"
#include "levelset/cut_fraction.hpp"
#include "levelset/material_removal.hpp"
#include "paths/cutter/tool_assembly.hpp"
#include "levelset/pocket_toolpath.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>

using namespace drom;
using namespace drom::levelset;
using drom::paths::ToolAssembly;
using drom::geometry::RemovalCriterion;
using drom::geometry::PartShape;

namespace {

// P(f < 0) for a uniform point of a tetrahedron on which f is linear with distinct vertex values f_i:
// 1 - sum_i (f_i)_+^3 / prod_{j != i} (f_i - f_j) (the B-spline form of the distribution of a linear
// function of Dirichlet weights). Independent of the geometric construction under test.
double divided_difference_fraction(const std::array<double, 4>& f) {
  double positive = 0;
  for (int i = 0; i < 4; ++i) {
    double denominator = 1;
    for (int j = 0; j < 4; ++j)
      if (j != i) denominator *= f[static_cast<std::size_t>(i)] - f[static_cast<std::size_t>(j)];
    positive += std::pow(std::max(f[static_cast<std::size_t>(i)], 0.0), 3) / denominator;
  }
  return 1 - positive;
}

}  // namespace

TEST(CutFraction, MatchesTheDividedDifferenceFormAndItsLimits) {
  std::mt19937 rng(29);
  std::normal_distribution<double> normal;
  int compared = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    std::array<double, 4> f{normal(rng), normal(rng), normal(rng), normal(rng)};
    double gap = 1e300;
    for (int i = 0; i < 4; ++i)
      for (int j = i + 1; j < 4; ++j) gap = std::min(gap, std::abs(f[static_cast<std::size_t>(i)] - f[static_cast<std::size_t>(j)]));
    const double ours = negative_fraction(f[0], f[1], f[2], f[3]);
    ASSERT_GE(ours, 0.0);
    ASSERT_LE(ours, 1.0);
    // Complement: f and -f split the tetrahedron between them.
    EXPECT_NEAR(ours + negative_fraction(-f[0], -f[1], -f[2], -f[3]), 1.0, 1e-12);
    // The vertex order does not matter.
    EXPECT_NEAR(ours, negative_fraction(f[2], f[0], f[3], f[1]), 1e-12);
    if (gap < 0.05) continue;  // the divided differences lose digits when values nearly coincide
    EXPECT_NEAR(ours, divided_difference_fraction(f), 1e-9) << f[0] << " " << f[1] << " " << f[2] << " " << f[3];
    ++compared;
  }
  EXPECT_GT(compared, 10000);
  // A plane through a vertex, or along a face: zero counts as outside.
  EXPECT_EQ(negative_fraction(0, 1, 2, 3), 0.0);
  EXPECT_EQ(negative_fraction(-1, 0, 0, 0), 1.0);
  EXPECT_EQ(negative_fraction(-1, -1, -1, 0), 1.0);
  // Corner tetrahedron: f = x + y + z - 1/2 on the unit tetrahedron is negative on a tetrahedron
  // scaled by 1/2, an eighth of the volume.
  EXPECT_NEAR(negative_fraction(-0.5, 0.5, 0.5, 0.5), 0.125, 1e-15);
  // Three negative: f = x - 1/2 is negative except at the corner tetrahedron x > 1/2 (1/8).
  EXPECT_NEAR(negative_fraction(-0.5, 0.5, -0.5, -0.5), 0.875, 1e-15);
  // Two and two: f = x + y - 1/2 is negative on {x + y < 1/2}, whose volume is
  // integral_0^1/2 (1 - s) s ds = 1/12, half the tetrahedron's 1/6.
  EXPECT_NEAR(negative_fraction(-0.5, 0.5, 0.5, -0.5), 0.5, 1e-15);
}

namespace {

struct LayerFractions {
  double removed_median = 0, removed_max = 0;  // pocket elements of the removed layers (corners apart)
  double corner_error = 0;                     // pocket corner elements against their exact share
  double floor_median = 1, floor_min = 1;      // elements under the floor
  double outside_min = 1;                      // every element outside the pocket
  double volume_error = 0;                     // deactivated volume against the pocket's, relative
};

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

// Machines a flat-end-mill pocket (one-way passes and the wall contour) through `mesh` and sorts the
// remaining fractions by where each element lies. Walls and floor must lie on element faces or
// between them as `floor_z` and the pocket's box say; the pocket's corners keep the tool's radius.
LayerFractions machine_pocket(const fem::Mesh& mesh, const PartShape& plate, const PocketSpec& pocket, const ToolAssembly& tool, double stepover,
                              double voxel) {
  MaterialRemoval removal(Workpiece::from_shape(plate), tool, voxel);
  const Toolpath path = pocket_toolpath(plate, pocket, tool, {PocketStrategy::OneWay, stepover, 10, 2, 5, 0.01});
  const PathTimeline timeline(path);
  removal.sweep(cutting_polylines(path, timeline, 0, timeline.length(), 0.01));
  const fem::MeshGeometry elements(mesh);
  std::vector<double> remaining;
  removal.update_remaining(elements, RemovalCriterion::VolumeFraction, remaining, false);
  const auto volumes = fem::element_volumes(mesh);
  const double top = plate.thickness(), floor_z = top - pocket.depth, R = tool.cutter.radius;
  const double x0 = pocket.x_min, x1 = pocket.x_min + pocket.length_x, y0 = pocket.y_min, y1 = pocket.y_min + pocket.length_y;
  const double exact = pocket.length_x * pocket.length_y * pocket.depth - 4 * (1 - M_PI / 4) * R * R * pocket.depth;
  LayerFractions out;
  std::vector<double> removed, under;
  double gone = 0;
  for (std::size_t e = 0; e < remaining.size(); ++e) {
    gone += (1 - remaining[e]) * volumes[e];
    const auto& box = elements.bounds(e);
    const bool in_plan = box.min().x() >= x0 - 1e-9 && box.max().x() <= x1 + 1e-9 && box.min().y() >= y0 - 1e-9 && box.max().y() <= y1 + 1e-9;
    const bool above = box.min().z() >= floor_z - 1e-9;
    if (!in_plan || !above) {
      out.outside_min = std::min(out.outside_min, remaining[e]);
      if (in_plan && box.max().z() <= floor_z + 1e-9) under.push_back(remaining[e]);
      continue;
    }
    // A corner fillet of the tool's radius stays in the pocket's corner elements.
    const bool corner = (box.min().x() < x0 + R || box.max().x() > x1 - R) && (box.min().y() < y0 + R || box.max().y() > y1 - R);
    if (corner) {
      const double fillet = (1 - M_PI / 4) * R * R * (box.max().z() - box.min().z());
      out.corner_error = std::max(out.corner_error, std::abs(remaining[e] - fillet / volumes[e]));
    } else {
      removed.push_back(remaining[e]);
      out.removed_max = std::max(out.removed_max, remaining[e]);
    }
  }
  out.removed_median = median(removed);
  out.floor_median = median(under);
  out.floor_min = under.empty() ? 1.0 : *std::min_element(under.begin(), under.end());
  out.volume_error = std::abs(gone - exact) / exact;
  return out;
}

void expect_exact(const LayerFractions& f, const char* what, double voxel) {
  std::printf("%s, voxel %.2f: removed layer median %.6f (max %.6f), corners off by %.2e, under the floor median %.6f (min %.6f), outside min %.6f, "
              "volume %.4f %%\n",
              what, voxel, f.removed_median, f.removed_max, f.corner_error, f.floor_median, f.floor_min, f.outside_min, 100 * f.volume_error);
  EXPECT_LE(f.removed_max, 1e-3) << what << " voxel " << voxel;
  EXPECT_LE(f.corner_error, 1e-3) << what << " voxel " << voxel;
  EXPECT_GE(f.floor_min, 1 - 1e-3) << what << " voxel " << voxel;
  EXPECT_GE(f.outside_min, 1 - 1e-3) << what << " voxel " << voxel;
  EXPECT_LE(f.volume_error, 1e-3) << what << " voxel " << voxel;
}

}  // namespace

// The table: the quick flat plate (1000 x 1000 x 10, 20 x 20 x 5 Hex20, 600 x 600 x 2 pocket
// whose floor and walls lie on element faces, flat R 12.5, 20 mm passes), at voxels that divide the
// 2 mm layers (0.5, 0.4) and voxels that do not (0.45, 0.33, 0.3). Before the fix: 0.0222 kept in the
// removed layer and 0.9889 under the floor at 0.45.
TEST(RemovalFraction, QuickFlatPlateIsExactAtEveryVoxelSize) {
  const PartShape plate = PartShape::plate(1000, 1000, 10);
  const fem::Mesh mesh = fem::make_structured_hex_mesh(plate, {20, 20, 5, 1.0});
  for (double voxel : {0.5, 0.45, 0.4, 0.33, 0.3})
    expect_exact(machine_pocket(mesh, plate, {200, 200, 600, 600, 2}, ToolAssembly::flat(12.5, 30), 20, voxel), "quick flat plate", voxel);
}

// Thickness-graded layers (bottom layer three times the top one): the floor on the face under the
// top layer, whose thickness (1.07 mm) no voxel below divides.
TEST(RemovalFraction, GradedPlateIsExact) {
  const PartShape plate = PartShape::plate(300, 300, 10);
  const fem::Mesh mesh = fem::make_structured_hex_mesh(plate, {6, 6, 5, 3.0});
  const auto levels = fem::thickness_levels(10, 5, 3.0);
  const double depth = 10 - levels[levels.size() - 2];
  for (double voxel : {0.45, 0.33, 0.21})
    expect_exact(machine_pocket(mesh, plate, {50, 50, 200, 200, depth}, ToolAssembly::flat(8, 30), 12, voxel), "graded plate", voxel);
}

// TetGen block with the floor plane in its PLC: the floor lies on tetrahedron faces, the walls cut
// through tetrahedra (planes, so still exact).
TEST(RemovalFraction, TetGenBlockWithAPocketIsExact) {
  const PartShape plate = PartShape::plate(120, 120, 10);
  const fem::Mesh mesh = fem::make_tet_mesh(fem::layered_box_plc({0, 0, 0}, {120, 120, 10}, {8.0}), {60.0, 1.4, 0});
  const PocketSpec pocket{20, 20, 80, 80, 2};
  const ToolAssembly tool = ToolAssembly::flat(6, 30);
  for (double voxel : {0.45, 0.3}) {
    MaterialRemoval removal(Workpiece::from_shape(plate), tool, voxel);
    const Toolpath path = pocket_toolpath(plate, pocket, tool, {PocketStrategy::OneWay, 10, 10, 2, 5, 0.01});
    const PathTimeline timeline(path);
    removal.sweep(cutting_polylines(path, timeline, 0, timeline.length(), 0.01));
    const fem::MeshGeometry elements(mesh);
    std::vector<double> remaining;
    removal.update_remaining(elements, RemovalCriterion::VolumeFraction, remaining, false);
    const auto volumes = fem::element_volumes(mesh);
    double gone = 0, removed_max = 0, under_min = 1;
    int removed_count = 0, under_count = 0;
    for (std::size_t e = 0; e < remaining.size(); ++e) {
      gone += (1 - remaining[e]) * volumes[e];
      const auto& box = elements.bounds(e);
      if (box.max().z() <= 8 + 1e-9) {
        under_min = std::min(under_min, remaining[e]);
        ++under_count;
      } else if (box.min().z() >= 8 - 1e-9 && box.min().x() >= 26 && box.max().x() <= 94 && box.min().y() >= 26 && box.max().y() <= 94) {
        removed_max = std::max(removed_max, remaining[e]);  // wholly inside the pocket, clear of its corners
        ++removed_count;
      }
    }
    const double exact = 80.0 * 80 * 2 - 4 * (1 - M_PI / 4) * 36 * 2;
    std::printf("TetGen block (%d tetrahedra), voxel %.2f: %d removed max %.2e, %d under the floor min %.8f, volume %.4f %%\n", mesh.element_count(),
                voxel, removed_count, removed_max, under_count, under_min, 100 * std::abs(gone - exact) / exact);
    ASSERT_GT(removed_count, 50);
    EXPECT_LE(removed_max, 1e-3) << voxel;
    EXPECT_GE(under_min, 1 - 1e-3) << voxel;
    EXPECT_LE(std::abs(gone - exact) / exact, 1e-3) << voxel;
  }
}

namespace {

// Area of the disc (centre (yc, zc), radius r) inside the rectangle [y0, y1] x [z0, z1], exactly:
// the z-chord of the disc clipped to [z0, z1], integrated in y piece by piece between the ordinates
// where the disc's boundary crosses z0 or z1.
double disc_in_rectangle(double yc, double zc, double r, double y0, double y1, double z0, double z1) {
  if (r <= 0 || y1 <= y0 || z1 <= z0) return 0;
  auto half = [&](double y) { return std::sqrt(std::max(0.0, r * r - (y - yc) * (y - yc))); };
  // Antiderivative of the half chord sqrt(r^2 - u^2).
  auto H = [&](double y) {
    const double u = std::clamp(y - yc, -r, r);
    return 0.5 * (u * std::sqrt(std::max(0.0, r * r - u * u)) + r * r * std::asin(u / r));
  };
  std::vector<double> cuts{y0, y1, yc - r, yc + r};
  for (double z : {z0, z1}) {
    const double d = std::abs(z - zc);
    if (d < r) {
      const double w = std::sqrt(r * r - d * d);
      cuts.push_back(yc - w);
      cuts.push_back(yc + w);
    }
  }
  std::sort(cuts.begin(), cuts.end());
  double area = 0;
  for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
    const double a = std::max(cuts[k], y0), b = std::min(cuts[k + 1], y1);
    if (b <= a) continue;
    const double m = 0.5 * (a + b), s = half(m);
    if (s <= 0) continue;
    // On this piece each end of the chord is either the disc's boundary or the rectangle's side,
    // and the chord may miss the rectangle altogether.
    const double lower = std::max(zc - s, z0), upper = std::min(zc + s, z1);
    if (upper <= lower) continue;
    const double arc = H(b) - H(a);  // integral of s over the piece
    const double top = zc + s < z1 ? zc * (b - a) + arc : z1 * (b - a);
    const double bottom = zc - s > z0 ? zc * (b - a) - arc : z0 * (b - a);
    area += top - bottom;
  }
  return area;
}

// Volume of {distance to the segment (x0s..x1s, yc, zc) <= R} inside the box, by the exact disc
// areas of each cross-section integrated along x with composite Gauss-Legendre (5 points, 4000
// panels over the caps; the section is constant between the segment's ends).
double groove_volume_in_box(double x0s, double x1s, double yc, double zc, double R, const Eigen::AlignedBox3d& box) {
  auto section = [&](double x) {
    const double dx = x < x0s ? x0s - x : (x > x1s ? x - x1s : 0.0);
    const double r2 = R * R - dx * dx;
    return r2 > 0 ? disc_in_rectangle(yc, zc, std::sqrt(r2), box.min().y(), box.max().y(), box.min().z(), box.max().z()) : 0.0;
  };
  static const double gx[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831, 0.9061798459386640};
  static const double gw[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665, 0.2369268850561891};
  auto integrate = [&](double a, double b, int panels) {
    if (b <= a) return 0.0;
    double sum = 0;
    const double h = (b - a) / panels;
    for (int p = 0; p < panels; ++p)
      for (int q = 0; q < 5; ++q) sum += 0.5 * h * gw[q] * section(a + h * (p + 0.5) + 0.5 * h * gx[q]);
    return sum;
  };
  const double a = box.min().x(), b = box.max().x();
  const double mid = std::max(0.0, std::min(b, x1s) - std::max(a, x0s)) * section(0.5 * (x0s + x1s));
  return integrate(std::max(a, x0s - R), std::min(b, x0s), 4000) + mid + integrate(std::max(a, x1s), std::min(b, x1s + R), 4000);
}

}  // namespace

// A ball groove (R 5, 2 mm deep, 30 mm long) whose surface cuts through 5 x 4 x 2 mm elements: each
// element's remaining fraction against its exact value, as the voxel shrinks.
TEST(RemovalFraction, CutsInsideElementsConvergeAtSecondOrder) {
  const PartShape block = PartShape::plate(50, 20, 4);
  const fem::Mesh mesh = fem::make_structured_hex_mesh(block, {10, 5, 2, 1.0});
  const fem::MeshGeometry elements(mesh);
  const auto volumes = fem::element_volumes(mesh);
  std::vector<double> exact(static_cast<std::size_t>(mesh.element_count()));
  for (std::size_t e = 0; e < exact.size(); ++e) {
    // The tip runs at z = 2, so the ball's centre at z = 7: the groove is the set within R of that
    // segment, clipped by the top face (the boxes lie inside the stock).
    exact[e] = 1 - groove_volume_in_box(10, 40, 10, 7, 5, elements.bounds(e)) / volumes[e];
  }
  double previous = 0;
  std::vector<double> orders;
  for (double voxel : {0.4, 0.2, 0.1, 0.05}) {
    MaterialRemoval removal(Workpiece::from_shape(block), ToolAssembly::ball(5, 20), voxel);
    removal.sweep({{{10, 10, 2}, {40, 10, 2}}});
    std::vector<double> remaining;
    removal.update_remaining(elements, RemovalCriterion::VolumeFraction, remaining, false);
    double worst = 0, sum = 0;
    int cut = 0;
    for (std::size_t e = 0; e < remaining.size(); ++e) {
      if (exact[e] <= 0 || exact[e] >= 1) continue;
      worst = std::max(worst, std::abs(remaining[e] - exact[e]));
      sum += std::abs(remaining[e] - exact[e]);
      ++cut;
    }
    std::printf("voxel %.3f: %d cut elements, max error %.3e, mean %.3e", voxel, cut, worst, sum / cut);
    if (previous > 0) {
      orders.push_back(std::log2(previous / worst));
      std::printf(", observed order %.2f", orders.back());
    }
    std::printf("\n");
    EXPECT_GE(cut, 15);
    previous = worst;
    if (voxel == 0.05) {
      EXPECT_LT(worst, 1e-3);
    }
  }
  // Second order: the level set interpolates the tool's distance linearly within a voxel, and the
  // lattice integrates that interpolant exactly.
  const double mean_order = (orders[0] + orders[1] + orders[2]) / 3;
  EXPECT_GT(mean_order, 1.6);
}
