#include "fem/shape_functions.hpp"

#include <gtest/gtest.h>

#include <cmath>

using namespace drom::fem;

TEST(ShapeFunctions, PartitionOfUnityAndNodalInterpolation) {
  for (auto type : {ElementType::Hex20, ElementType::Hex27, ElementType::Tet10}) {
    const Eigen::MatrixX3d ref = reference_nodes(type);
    Eigen::VectorXd N;
    Eigen::MatrixX3d dN;
    for (Eigen::Index a = 0; a < ref.rows(); ++a) {
      shape_functions(type, ref.row(a).transpose(), N, dN);
      for (Eigen::Index b = 0; b < ref.rows(); ++b) EXPECT_NEAR(N[b], a == b ? 1.0 : 0.0, 1e-14) << element_name(type);
    }
    shape_functions(type, Eigen::Vector3d(0.1, 0.2, 0.3), N, dN);
    EXPECT_NEAR(N.sum(), 1.0, 1e-14);
    EXPECT_NEAR(dN.colwise().sum().norm(), 0.0, 1e-13);
  }
}

TEST(ShapeFunctions, GradientsMatchFiniteDifferences) {
  for (auto type : {ElementType::Hex20, ElementType::Hex27, ElementType::Tet10}) {
    const Eigen::Vector3d xi(0.13, 0.21, 0.17);
    Eigen::VectorXd N, Np, Nm;
    Eigen::MatrixX3d dN, unused;
    shape_functions(type, xi, N, dN);
    for (int k = 0; k < 3; ++k) {
      Eigen::Vector3d h = Eigen::Vector3d::Zero();
      h[k] = 1e-6;
      shape_functions(type, xi + h, Np, unused);
      shape_functions(type, xi - h, Nm, unused);
      EXPECT_LT(((Np - Nm) / 2e-6 - dN.col(k)).cwiseAbs().maxCoeff(), 1e-8) << element_name(type);
    }
  }
}

TEST(Quadrature, TetRuleIntegratesMonomialsExactly) {
  // int_T x^a y^b z^c = a! b! c! / (a + b + c + 3)!
  auto fact = [](int n) { double f = 1; for (int i = 2; i <= n; ++i) f *= i; return f; };
  for (int degree : {2, 4, 8}) {
    const auto rule = tet_rule(degree);
    for (int a = 0; a <= degree; ++a)
      for (int b = 0; a + b <= degree; ++b)
        for (int c = 0; a + b + c <= degree; ++c) {
          double sum = 0;
          for (const auto& q : rule) sum += q.weight * std::pow(q.xi.x(), a) * std::pow(q.xi.y(), b) * std::pow(q.xi.z(), c);
          EXPECT_NEAR(sum, fact(a) * fact(b) * fact(c) / fact(a + b + c + 3), 1e-14) << degree << " " << a << b << c;
        }
  }
}

TEST(Quadrature, HexRuleIntegratesMonomialsExactly) {
  for (int n = 1; n <= 6; ++n) {
    const auto rule = hex_gauss_rule(n);
    for (int a = 0; a <= 2 * n - 1; ++a) {
      double sum = 0;
      for (const auto& q : rule) sum += q.weight * std::pow(q.xi.x(), a);
      const double exact = a % 2 ? 0.0 : 8.0 / (a + 1);
      EXPECT_NEAR(sum, exact, 1e-13) << n << " " << a;
    }
  }
}
