#pragma once
// Quadratic Lagrange/serendipity shape functions and the quadrature rules used with them.
#include "fem/mesh.hpp"

#include <Eigen/Core>

#include <vector>

namespace drom::fem {

struct QuadraturePoint {
  Eigen::Vector3d xi;  // reference coordinates
  double weight;
};

// 1D Gauss-Legendre rule with n points on [-1, 1] (n = 1..16).
void gauss_legendre(int n, std::vector<double>& x, std::vector<double>& w);

// Tensor Gauss-Legendre rule with n points per direction on [-1, 1]^3 (n = 1..8).
std::vector<QuadraturePoint> hex_gauss_rule(int n);
// Anisotropic tensor rule: nx, ny, nz points along the three reference directions.
std::vector<QuadraturePoint> hex_gauss_rule(int nx, int ny, int nz);
// Rule on the unit tetrahedron exact for polynomials of total degree `degree`.
// Degree <= 2 uses the classic 4-point rule; higher degrees a collapsed (Duffy) Gauss product.
std::vector<QuadraturePoint> tet_rule(int degree);

// Rule for an element type exact for polynomials of the given degree in each reference variable.
std::vector<QuadraturePoint> quadrature_rule(ElementType type, int degree);

// Shape function values N (n) and reference gradients dN (n x 3) at a reference point.
void shape_functions(ElementType type, const Eigen::Vector3d& xi, Eigen::VectorXd& N, Eigen::MatrixX3d& dN);

// Reference coordinates of each node (n x 3), in VTK order.
Eigen::MatrixX3d reference_nodes(ElementType type);

}  // namespace drom::fem
