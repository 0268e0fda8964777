// Locating points on a surface seen from above, and interpolating with its faces' shape functions.
#include "reduce/surface_mesh.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace drom::reduce;

namespace {

// A structured grid of quadratic faces over [0, 3] x [0, 2] with a curved altitude; `kind` 8, 9 or 6
// (each quad cut in two triangles).
SurfaceMesh grid(int kind, Eigen::VectorXd& f, const std::function<double(double, double)>& field) {
  const int ex = 3, ey = 2, nx = 2 * ex + 1, ny = 2 * ey + 1;
  Eigen::Matrix3Xd nodes(3, nx * ny);
  auto id = [&](int i, int j) { return j * nx + i; };
  f.resize(nx * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      const double x = 0.5 * i, y = 0.5 * j;
      nodes.col(id(i, j)) = Eigen::Vector3d(x, y, 0.1 * x * y);
      f[id(i, j)] = field(x, y);
    }
  std::vector<int> faces;
  for (int ey_ = 0; ey_ < ey; ++ey_)
    for (int ex_ = 0; ex_ < ex; ++ex_) {
      const int i = 2 * ex_, j = 2 * ey_;
      if (kind == 6) {
        for (int v : {id(i, j), id(i + 2, j), id(i + 2, j + 2), id(i + 1, j), id(i + 2, j + 1), id(i + 1, j + 1)}) faces.push_back(v);
        for (int v : {id(i, j), id(i + 2, j + 2), id(i, j + 2), id(i + 1, j + 1), id(i + 1, j + 2), id(i, j + 1)}) faces.push_back(v);
      } else {
        for (int v : {id(i, j), id(i + 2, j), id(i + 2, j + 2), id(i, j + 2), id(i + 1, j), id(i + 2, j + 1), id(i + 1, j + 2), id(i, j + 1)}) faces.push_back(v);
        if (kind == 9) faces.push_back(id(i + 1, j + 1));
      }
    }
  return {nodes, faces, kind};
}

}  // namespace

TEST(SurfaceMesh, QuadraticFacesInterpolateQuadraticsExactlyWithTheirSlopes) {
  // A complete quadratic is reproduced by Quad8, Quad9 and Tri6 on straight-sided faces.
  auto q = [](double x, double y) { return 1 + 2 * x - y + 0.5 * x * x - 0.3 * x * y + 0.7 * y * y; };
  auto qx = [](double x, double y) { return 2 + x - 0.3 * y; };
  auto qy = [](double x, double y) { return -1 - 0.3 * x + 1.4 * y; };
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> ux(0, 3), uy(0, 2);
  for (int kind : {8, 9, 6}) {
    Eigen::VectorXd f;
    const SurfaceMesh mesh = grid(kind, f, q);
    for (int s = 0; s < 200; ++s) {
      const double x = ux(rng), y = uy(rng);
      const auto p = mesh.locate(x, y);
      ASSERT_TRUE(p) << kind << " at " << x << ", " << y;
      double v = 0, vx = 0, vy = 0;
      for (int k = 0; k < p->count; ++k) {
        v += p->weights[static_cast<std::size_t>(k)] * f[p->nodes[static_cast<std::size_t>(k)]];
        vx += p->dx[static_cast<std::size_t>(k)] * f[p->nodes[static_cast<std::size_t>(k)]];
        vy += p->dy[static_cast<std::size_t>(k)] * f[p->nodes[static_cast<std::size_t>(k)]];
      }
      EXPECT_NEAR(v, q(x, y), 1e-12);
      EXPECT_NEAR(vx, qx(x, y), 1e-10);
      EXPECT_NEAR(vy, qy(x, y), 1e-10);
      EXPECT_NEAR(mesh.nominal_altitude(*p), 0.1 * x * y, 1e-12);
    }
    EXPECT_FALSE(mesh.locate(-0.01, 1.0));
    EXPECT_FALSE(mesh.locate(1.0, 2.01));
    EXPECT_FALSE(mesh.locate(std::nan(""), 1.0));
  }
}

TEST(SurfaceMesh, RejectsMalformedFaces) {
  Eigen::Matrix3Xd nodes = Eigen::Matrix3Xd::Zero(3, 4);
  EXPECT_THROW(SurfaceMesh(nodes, {0, 1, 2, 3, 4}, 5), std::invalid_argument);
  EXPECT_THROW(SurfaceMesh(nodes, {0, 1, 2, 9}, 4), std::invalid_argument);
  EXPECT_THROW(SurfaceMesh(nodes, {0, 1, 2}, 4), std::invalid_argument);
}
