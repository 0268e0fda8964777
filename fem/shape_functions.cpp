#include "fem/shape_functions.hpp"

#include <Eigen/Dense>

#include <cmath>
#include <stdexcept>

namespace drom::fem {

int nodes_per_element(ElementType type) {
  switch (type) {
    case ElementType::Hex20: return 20;
    case ElementType::Hex27: return 27;
    case ElementType::Tet10: break;
  }
  return 10;
}
const char* element_name(ElementType type) {
  switch (type) {
    case ElementType::Hex20: return "hex20";
    case ElementType::Hex27: return "hex27";
    case ElementType::Tet10: break;
  }
  return "tet10";
}

void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w) {
  if (n < 1 || n > 16) throw std::invalid_argument("gauss_legendre: 1..16 points");
  x.assign(n, 0.0);
  w.assign(n, 0.0);
  // Newton on P_n from Chebyshev guesses: converges to machine precision in a few steps.
  for (int i = 0; i < n; ++i) {
    double z = std::cos(M_PI * (i + 0.75) / (n + 0.5));
    double dp = 0.0;
    for (int it = 0; it < 100; ++it) {
      double p0 = 1.0, p1 = z;
      for (int k = 2; k <= n; ++k) {
        const double p2 = ((2.0 * k - 1.0) * z * p1 - (k - 1.0) * p0) / k;
        p0 = p1;
        p1 = p2;
      }
      const double pn = n == 1 ? z : p1;
      const double pnm1 = n == 1 ? 1.0 : p0;
      dp = n * (z * pn - pnm1) / (z * z - 1.0);
      const double dz = pn / dp;
      z -= dz;
      if (std::abs(dz) < 1e-16) break;
    }
    x[i] = z;
    w[i] = 2.0 / ((1.0 - z * z) * dp * dp);
  }
}

namespace {

// Hex reference nodes in VTK order: corners, edge midpoints (Hex20 stops here), then the face
// centres (-x, +x, -y, +y, -z, +z, as vtkTriQuadraticHexahedron's parametric coordinates give them)
// and the body centre.
const double kHexRef[27][3] = {
    {-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, 1, 1}, {-1, 1, 1},
    {0, -1, -1},  {1, 0, -1},  {0, 1, -1}, {-1, 0, -1}, {0, -1, 1},  {1, 0, 1},  {0, 1, 1}, {-1, 0, 1},
    {-1, -1, 0},  {1, -1, 0},  {1, 1, 0},  {-1, 1, 0},  {-1, 0, 0},  {1, 0, 0},  {0, -1, 0}, {0, 1, 0},
    {0, 0, -1},   {0, 0, 1},   {0, 0, 0}};

// 1D quadratic Lagrange polynomial with node at c in {-1, 0, 1}, and its derivative.
double lagrange2(double c, double x) { return c == 0 ? 1 - x * x : 0.5 * x * (x + c); }
double lagrange2_derivative(double c, double x) { return c == 0 ? -2 * x : x + 0.5 * c; }

void hex27(const Eigen::Vector3d& p, Eigen::VectorXd& N, Eigen::MatrixX3d& dN) {
  N.resize(27);
  dN.resize(27, 3);
  for (int a = 0; a < 27; ++a) {
    const double lx = lagrange2(kHexRef[a][0], p[0]), ly = lagrange2(kHexRef[a][1], p[1]), lz = lagrange2(kHexRef[a][2], p[2]);
    N[a] = lx * ly * lz;
    dN(a, 0) = lagrange2_derivative(kHexRef[a][0], p[0]) * ly * lz;
    dN(a, 1) = lx * lagrange2_derivative(kHexRef[a][1], p[1]) * lz;
    dN(a, 2) = lx * ly * lagrange2_derivative(kHexRef[a][2], p[2]);
  }
}

const double kTetRef[10][3] = {{0, 0, 0},   {1, 0, 0},   {0, 1, 0},   {0, 0, 1},   {.5, 0, 0},
                               {.5, .5, 0}, {0, .5, 0},  {0, 0, .5},  {.5, 0, .5}, {0, .5, .5}};

void hex20(const Eigen::Vector3d& p, Eigen::VectorXd& N, Eigen::MatrixX3d& dN) {
  N.resize(20);
  dN.resize(20, 3);
  for (int a = 0; a < 20; ++a) {
    const double xa = kHexRef[a][0], ya = kHexRef[a][1], za = kHexRef[a][2];
    const double x = p[0], y = p[1], z = p[2];
    if (a < 8) {
      const double fx = 1 + x * xa, fy = 1 + y * ya, fz = 1 + z * za;
      const double s = x * xa + y * ya + z * za - 2;
      N[a] = 0.125 * fx * fy * fz * s;
      dN(a, 0) = 0.125 * xa * fy * fz * (s + fx);
      dN(a, 1) = 0.125 * ya * fx * fz * (s + fy);
      dN(a, 2) = 0.125 * za * fx * fy * (s + fz);
    } else if (xa == 0) {
      const double fy = 1 + y * ya, fz = 1 + z * za;
      N[a] = 0.25 * (1 - x * x) * fy * fz;
      dN(a, 0) = -0.5 * x * fy * fz;
      dN(a, 1) = 0.25 * (1 - x * x) * ya * fz;
      dN(a, 2) = 0.25 * (1 - x * x) * fy * za;
    } else if (ya == 0) {
      const double fx = 1 + x * xa, fz = 1 + z * za;
      N[a] = 0.25 * (1 - y * y) * fx * fz;
      dN(a, 0) = 0.25 * (1 - y * y) * xa * fz;
      dN(a, 1) = -0.5 * y * fx * fz;
      dN(a, 2) = 0.25 * (1 - y * y) * fx * za;
    } else {
      const double fx = 1 + x * xa, fy = 1 + y * ya;
      N[a] = 0.25 * (1 - z * z) * fx * fy;
      dN(a, 0) = 0.25 * (1 - z * z) * xa * fy;
      dN(a, 1) = 0.25 * (1 - z * z) * fx * ya;
      dN(a, 2) = -0.5 * z * fx * fy;
    }
  }
}

void tet10(const Eigen::Vector3d& p, Eigen::VectorXd& N, Eigen::MatrixX3d& dN) {
  N.resize(10);
  dN.resize(10, 3);
  const double L[4] = {1 - p[0] - p[1] - p[2], p[0], p[1], p[2]};
  // dL_i/dxi_k
  const double dL[4][3] = {{-1, -1, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
  for (int a = 0; a < 4; ++a) {
    N[a] = L[a] * (2 * L[a] - 1);
    for (int k = 0; k < 3; ++k) dN(a, k) = (4 * L[a] - 1) * dL[a][k];
  }
  const int edges[6][2] = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}};
  for (int m = 0; m < 6; ++m) {
    const int i = edges[m][0], j = edges[m][1];
    N[4 + m] = 4 * L[i] * L[j];
    for (int k = 0; k < 3; ++k) dN(4 + m, k) = 4 * (dL[i][k] * L[j] + L[i] * dL[j][k]);
  }
}

}  // namespace

std::vector<QuadraturePoint> hex_gauss_rule(int n) { return hex_gauss_rule(n, n, n); }

std::vector<QuadraturePoint> hex_gauss_rule(int nx, int ny, int nz) {
  std::vector<double> x, wx, y, wy, z, wz;
  gauss_legendre(nx, x, wx);
  gauss_legendre(ny, y, wy);
  gauss_legendre(nz, z, wz);
  std::vector<QuadraturePoint> rule;
  rule.reserve(static_cast<std::size_t>(nx * ny * nz));
  for (int k = 0; k < nz; ++k)
    for (int j = 0; j < ny; ++j)
      for (int i = 0; i < nx; ++i) rule.push_back({Eigen::Vector3d(x[i], y[j], z[k]), wx[i] * wy[j] * wz[k]});
  return rule;
}

std::vector<QuadraturePoint> tet_rule(int degree) {
  if (degree <= 2) {
    const double a = 0.5854101966249685, b = 0.1381966011250105;
    return {{{b, b, b}, 1.0 / 24}, {{a, b, b}, 1.0 / 24}, {{b, a, b}, 1.0 / 24}, {{b, b, a}, 1.0 / 24}};
  }
  // Duffy collapse of the unit cube: the Jacobian adds two degrees in the first variable.
  const int n = (degree + 2) / 2 + 1;
  std::vector<double> x, w;
  gauss_legendre(n, x, w);
  std::vector<QuadraturePoint> rule;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j)
      for (int k = 0; k < n; ++k) {
        const double u = 0.5 * (x[i] + 1), v = 0.5 * (x[j] + 1), t = 0.5 * (x[k] + 1);
        const double p0 = u, p1 = v * (1 - u), p2 = t * (1 - u) * (1 - v);
        const double jac = (1 - u) * (1 - u) * (1 - v);
        rule.push_back({Eigen::Vector3d(p0, p1, p2), 0.125 * w[i] * w[j] * w[k] * jac});
      }
  return rule;
}

std::vector<QuadraturePoint> quadrature_rule(ElementType type, int degree) {
  if (is_hex(type)) return hex_gauss_rule(std::max(1, (degree + 2) / 2));
  return tet_rule(degree);
}

void shape_functions(ElementType type, const Eigen::Vector3d& xi, Eigen::VectorXd& N, Eigen::MatrixX3d& dN) {
  switch (type) {
    case ElementType::Hex20: hex20(xi, N, dN); return;
    case ElementType::Hex27: hex27(xi, N, dN); return;
    case ElementType::Tet10: tet10(xi, N, dN); return;
  }
}

Eigen::MatrixX3d reference_nodes(ElementType type) {
  const int n = nodes_per_element(type);
  Eigen::MatrixX3d r(n, 3);
  for (int a = 0; a < n; ++a)
    for (int k = 0; k < 3; ++k) r(a, k) = is_hex(type) ? kHexRef[a][k] : kTetRef[a][k];
  return r;
}

Eigen::Matrix3Xd Mesh::element_nodes(int e) const {
  const auto conn = element(e);
  Eigen::Matrix3Xd X(3, static_cast<Eigen::Index>(conn.size()));
  for (std::size_t a = 0; a < conn.size(); ++a) X.col(static_cast<Eigen::Index>(a)) = nodes[static_cast<std::size_t>(conn[a])];
  return X;
}

Eigen::Vector3d Mesh::centroid(int e) const {
  const auto conn = element(e);
  const int corners = is_hex(type) ? 8 : 4;
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int a = 0; a < corners; ++a) c += nodes[static_cast<std::size_t>(conn[static_cast<std::size_t>(a)])];
  return c / corners;
}

std::vector<double> element_volumes(const Mesh& mesh) {
  const auto rule = quadrature_rule(mesh.type, 4);
  std::vector<double> volumes(static_cast<std::size_t>(mesh.element_count()));
  Eigen::VectorXd N;
  Eigen::MatrixX3d dN;
  for (int e = 0; e < mesh.element_count(); ++e) {
    const Eigen::Matrix3Xd X = mesh.element_nodes(e);
    double v = 0;
    for (const auto& q : rule) {
      shape_functions(mesh.type, q.xi, N, dN);
      v += q.weight * (X * dN).determinant();
    }
    volumes[static_cast<std::size_t>(e)] = v;
  }
  return volumes;
}

}  // namespace drom::fem
