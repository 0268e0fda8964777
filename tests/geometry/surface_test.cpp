// Free-form surfaces: evaluation against independent references (de Casteljau, OpenCASCADE's own
// B-spline evaluator, closed-form curvatures), and the [surface] reader's errors.
#include "geometry/local_geometry.hpp"
#include "geometry/nurbs_surface.hpp"
#include "geometry/surface_grid.hpp"
#include "geometry/surface_input.hpp"
#include "support/input_error.hpp"
#include "tests/geometry/test_surfaces.hpp"

#include <Eigen/Geometry>
#include <Geom_BSplineSurface.hxx>
#include <TColStd_Array1OfInteger.hxx>
#include <TColStd_Array1OfReal.hxx>
#include <TColStd_Array2OfReal.hxx>
#include <TColgp_Array2OfPnt.hxx>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

namespace {

using drom::geometry::NurbsSurface;

// de Casteljau in both directions: the textbook reference for a Bézier patch.
Eigen::Vector3d de_casteljau(const NurbsSurface& s, double u, double v) {
  std::vector<Eigen::Vector3d> row(static_cast<std::size_t>(s.count_u()));
  for (int i = 0; i < s.count_u(); ++i) {
    std::vector<Eigen::Vector3d> p(s.points().begin() + i * s.count_v(), s.points().begin() + (i + 1) * s.count_v());
    for (std::size_t k = p.size() - 1; k > 0; --k)
      for (std::size_t j = 0; j < k; ++j) p[j] = (1 - v) * p[j] + v * p[j + 1];
    row[static_cast<std::size_t>(i)] = p[0];
  }
  for (std::size_t k = row.size() - 1; k > 0; --k)
    for (std::size_t j = 0; j < k; ++j) row[j] = (1 - u) * row[j] + u * row[j + 1];
  return row[0];
}

TEST(NurbsSurface, BezierMatchesDeCasteljauAndFiniteDifferences) {
  for (const auto& s : {drom::tests::rubio_surface(), drom::tests::choi_surface()}) {
    for (double u : {0.0, 0.13, 0.5, 0.77, 1.0})
      for (double v : {0.0, 0.31, 0.5, 0.9, 1.0}) {
        EXPECT_LT((s.point(u, v) - de_casteljau(s, u, v)).norm(), 1e-12);
        const auto d = s.derivatives(u, v);
        EXPECT_LT((d.point - de_casteljau(s, u, v)).norm(), 1e-12);
        const double h = 1e-6, uc = std::clamp(u, h, 1 - h), vc = std::clamp(v, h, 1 - h);
        const auto c = s.derivatives(uc, vc);
        const Eigen::Vector3d fu = (s.point(uc + h, vc) - s.point(uc - h, vc)) / (2 * h), fv = (s.point(uc, vc + h) - s.point(uc, vc - h)) / (2 * h);
        EXPECT_LT((c.du - fu).norm(), 1e-6 * (1 + fu.norm()));
        EXPECT_LT((c.dv - fv).norm(), 1e-6 * (1 + fv.norm()));
        const auto fd = [&](double a, double b) { return s.derivatives(a, b); };
        EXPECT_LT((c.duu - (fd(uc + h, vc).du - fd(uc - h, vc).du) / (2 * h)).norm(), 1e-5 * (1 + c.duu.norm()));
        EXPECT_LT((c.duv - (fd(uc, vc + h).du - fd(uc, vc - h).du) / (2 * h)).norm(), 1e-5 * (1 + c.duv.norm()));
        EXPECT_LT((c.dvv - (fd(uc, vc + h).dv - fd(uc, vc - h).dv) / (2 * h)).norm(), 1e-5 * (1 + c.dvv.norm()));
      }
  }
}

// A rational bicubic B-spline with interior knots, evaluated by OpenCASCADE (Geom_BSplineSurface::D2)
// as the independent reference: point and every first and second derivative.
TEST(NurbsSurface, RationalBsplineMatchesOpenCascade) {
  const int nu = 6, nv = 5, pu = 3, pv = 2;
  std::vector<Eigen::Vector3d> points;
  std::vector<double> weights;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      points.emplace_back(10.0 * i + std::sin(j), 7.0 * j + 0.3 * i * i, 3.0 * std::sin(0.9 * i) * std::cos(0.7 * j));
      weights.push_back(1.0 + 0.25 * std::sin(1.3 * i + 0.4 * j) * std::sin(1.3 * i + 0.4 * j));
    }
  const std::vector<double> ku = {0, 0, 0, 0, 0.3, 0.55, 1, 1, 1, 1}, kv = {-1, -1, -1, 0.5, 0.5, 2, 2, 2};
  const NurbsSurface s(pu, pv, ku, kv, nu, nv, points, weights);
  TColgp_Array2OfPnt poles(1, nu, 1, nv);
  TColStd_Array2OfReal w(1, nu, 1, nv);
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      const auto& p = points[static_cast<std::size_t>(i * nv + j)];
      poles.SetValue(i + 1, j + 1, gp_Pnt(p.x(), p.y(), p.z()));
      w.SetValue(i + 1, j + 1, weights[static_cast<std::size_t>(i * nv + j)]);
    }
  TColStd_Array1OfReal uk(1, 4), vk(1, 3);
  TColStd_Array1OfInteger um(1, 4), vm(1, 3);
  const double ukv[] = {0, 0.3, 0.55, 1}, vkv[] = {-1, 0.5, 2};
  const int umv[] = {4, 1, 1, 4}, vmv[] = {3, 2, 3};
  for (int i = 0; i < 4; ++i) uk.SetValue(i + 1, ukv[i]), um.SetValue(i + 1, umv[i]);
  for (int i = 0; i < 3; ++i) vk.SetValue(i + 1, vkv[i]), vm.SetValue(i + 1, vmv[i]);
  const Geom_BSplineSurface occt(poles, w, uk, vk, um, vm, pu, pv);
  const auto E = [](const gp_Vec& v) { return Eigen::Vector3d(v.X(), v.Y(), v.Z()); };
  for (int a = 0; a <= 20; ++a)
    for (int b = 0; b <= 20; ++b) {
      const double u = a / 20.0, v = -1 + 3 * b / 20.0;
      gp_Pnt p;
      gp_Vec du, dv, duu, dvv, duv;
      occt.D2(u, v, p, du, dv, duu, dvv, duv);
      const auto d = s.derivatives(u, v);
      EXPECT_LT((d.point - Eigen::Vector3d(p.X(), p.Y(), p.Z())).norm(), 1e-11) << u << " " << v;
      EXPECT_LT((d.du - E(du)).norm(), 1e-9 * (1 + d.du.norm()));
      EXPECT_LT((d.dv - E(dv)).norm(), 1e-9 * (1 + d.dv.norm()));
      EXPECT_LT((d.duu - E(duu)).norm(), 1e-8 * (1 + d.duu.norm()));
      EXPECT_LT((d.duv - E(duv)).norm(), 1e-8 * (1 + d.duv.norm()));
      EXPECT_LT((d.dvv - E(dvv)).norm(), 1e-8 * (1 + d.dvv.norm()));
    }
  // The unit-domain copy is the same surface.
  const NurbsSurface unit = s.with_unit_domain();
  EXPECT_LT((unit.point(0.25, 0.6) - s.point(0.25, -1 + 3 * 0.6)).norm(), 1e-12);
}

// A quarter cylinder of radius 7 as an exact rational quadratic: curvatures 1/7 and 0 everywhere.
TEST(LocalGeometry, RationalCylinderCurvatures) {
  const double R = 7, c = std::sqrt(0.5);
  std::vector<Eigen::Vector3d> points;
  for (const auto& p : {Eigen::Vector2d(R, 0), Eigen::Vector2d(R, R), Eigen::Vector2d(0, R)})
    for (double z : {0.0, 20.0}) points.emplace_back(p.x(), p.y(), z);
  const auto s = NurbsSurface::bezier(3, 2, points, {1, 1, c, c, 1, 1});
  for (double u : {0.0, 0.2, 0.5, 0.8, 1.0}) {
    const auto g = drom::geometry::local_geometry(s.derivatives(u, 0.4));
    EXPECT_NEAR(std::hypot(g.point.x(), g.point.y()), R, 1e-12);
    EXPECT_NEAR(std::abs(g.kappa1 + g.kappa2), 1 / R, 1e-10);
    EXPECT_NEAR(g.gaussian, 0, 1e-12);
    EXPECT_NEAR(std::abs(g.mean), 0.5 / R, 1e-10);
    // Along the circle the normal curvature is the full 1/R, along the axis zero.
    const Eigen::Vector3d along_axis(0, 0, 1), around = g.normal.cross(along_axis);
    EXPECT_NEAR(std::abs(drom::geometry::normal_curvature(g, around)), 1 / R, 1e-10);
    EXPECT_NEAR(drom::geometry::normal_curvature(g, along_axis), 0, 1e-12);
  }
}

TEST(LocalGeometry, SlopeAndAzimuthConventions) {
  const Eigen::Vector3d z(0, 0, 1);
  const double s60 = std::numbers::pi / 3;
  const Eigen::Vector3d n(std::sin(s60), 0, std::cos(s60));
  EXPECT_NEAR(drom::geometry::slope(n, z), s60, 1e-14);
  EXPECT_NEAR(drom::geometry::slope(-n, z), s60, 1e-14);
  EXPECT_NEAR(drom::geometry::steepest_azimuth(n), 0, 1e-14);
  EXPECT_NEAR(drom::geometry::steepest_azimuth(Eigen::Vector3d(-1, 1, 1).normalized()), -std::numbers::pi / 4, 1e-14);
  EXPECT_EQ(drom::geometry::steepest_azimuth(z), 0);
}

TEST(SurfaceGrid, CellCentresAndNodes) {
  const auto s = drom::tests::rubio_surface();
  const auto centres = drom::geometry::sample_grid(s, 80, 80, drom::geometry::GridPlacement::cell_centres);
  EXPECT_EQ(centres.size(), 6400u);
  EXPECT_DOUBLE_EQ(centres.u[centres.index(0, 0)], 0.5 / 80);
  EXPECT_DOUBLE_EQ(centres.v[centres.index(79, 3)], 3.5 / 80);
  EXPECT_DOUBLE_EQ(centres.u[centres.index(79, 3)], 79.5 / 80);
  const auto nodes = drom::geometry::sample_grid(s, 4, 2, drom::geometry::GridPlacement::nodes);
  EXPECT_EQ(nodes.size(), 15u);
  EXPECT_LT((nodes.samples[nodes.index(4, 2)].point - s.point(1, 1)).norm(), 1e-12);
  // Rubio's u iso-curves run about 80 mm, its v iso-curves about 40 mm.
  const auto [cu, cv] = drom::geometry::cells_for_step(s, 0.5);
  EXPECT_GT(cu, 160);
  EXPECT_LT(cu, 200);
  EXPECT_GT(cv, 70);
  EXPECT_LT(cv, 110);
}

std::string reader_error(const std::string& text) {
  drom::TomlReader r(text, "case.toml");
  try {
    drom::geometry::read_surface(r, "surface", ".");
    r.finish();
  } catch (const drom::InputError& e) {
    return e.what();
  }
  return "";
}

TEST(SurfaceInput, ReadsControlNetsAndNamesBadKeys) {
  drom::TomlReader r(drom::tests::rubio_toml(), "rubio.toml");
  const auto in = drom::geometry::read_surface(r, "surface", ".");
  r.finish();
  EXPECT_LT((in.surface.point(0.3, 0.6) - drom::tests::rubio_surface().point(0.3, 0.6)).norm(), 1e-14);
  EXPECT_EQ(in.description, "Bézier 3 x 3");
  // A collapsed edge: every point of the u = 0 row at one place.
  const std::string degenerate =
      "[surface]\nkind = \"bezier\"\ncount = [2, 2]\npoints = [[0, 0, 0], [0, 0, 0],\n  [10, 0, 0], [10, 10, 0]]\n";
  EXPECT_NE(reader_error(degenerate).find("case.toml:4: surface.points: degenerate patch"), std::string::npos) << reader_error(degenerate);
  EXPECT_NE(reader_error("[surface]\nkind = \"bezier\"\ncount = [2, 2]\npoints = [[0, 0, 0], [0, 1, 0], [1, 0]]\n").find("case.toml:4: surface.points.2: row 3"),
            std::string::npos);
  EXPECT_NE(reader_error("[surface]\nkind = \"bezier\"\ncount = [2, 2]\npoints = [[0, 0, 0], [0, 1, 0], [1, 0, 0]]\n").find("3 control points given"),
            std::string::npos);
  EXPECT_NE(reader_error("[surface]\nkind = \"bspline\"\ncount = [3, 3]\ndegree_u = 2\ndegree_v = 1\nknots_u = [0, 0, 0, 2, 1, 1]\n"
                         "points = [[0,0,0],[0,1,0],[0,2,0],[1,0,0],[1,1,0],[1,2,1],[2,0,0],[2,1,0],[2,2,0]]\n")
                .find("case.toml:6: surface.knots_u"),
            std::string::npos);
  EXPECT_NE(reader_error("[surface]\nkind = \"spline\"\n").find("case.toml:2: surface.kind"), std::string::npos);
  EXPECT_NE(reader_error("[surface]\nkind = \"step\"\nstep = \"nowhere.step\"\n").find("case.toml:3: surface.step: ./nowhere.step: no such STEP file"),
            std::string::npos)
      << reader_error("[surface]\nkind = \"step\"\nstep = \"nowhere.step\"\n");
}

}  // namespace
