#pragma once
// Element-level operators of small-strain isotropic elasticity with an initial stress:
// stiffness K_e = int B^T C B, initial-stress load f_e = int B^T sigma, and strain recovery.
// Voigt order: xx, yy, zz, yz, xz, xy with engineering shear strains.
#include "fem/mesh.hpp"
#include "geometry/part_shape.hpp"
#include "fem/residual_stress.hpp"
#include "fem/shape_functions.hpp"

#include <Eigen/Core>

#include <span>
#include <string>
#include <unordered_map>
#include <vector>

namespace drom::fem {

using Vector6d = Eigen::Matrix<double, 6, 1>;
using Matrix6d = Eigen::Matrix<double, 6, 6>;

struct Material {
  double young_modulus = 71700.0;  // MPa
  double poisson_ratio = 0.33;
  Matrix6d elasticity() const;
};

Vector6d to_voigt(const Eigen::Matrix3d& stress);
double von_mises(const Vector6d& stress);

class ElementOperators {
 public:
  ElementOperators(const Mesh& mesh, const Material& material);

  // Element stiffness (3n x 3n, dofs node-major). Elements that are translated copies of one
  // another share one computation: structured plates have only a handful of distinct shapes.
  const Eigen::MatrixXd& stiffness(int e);
  // int_e B^T sigma_R for each profile (3n x P), with a rule exact for the profile's degree.
  Eigen::MatrixXd stress_load(int e, std::span<const StressProfile> profiles, const PartShape& shape) const;
  // Average over the element's quadrature points of C eps(u_e) + sigma_R (u_e: element dofs).
  Vector6d mean_stress(int e, const Eigen::VectorXd& element_displacement, const StressProfile* profile,
                       const PartShape& shape) const;
  // The same stress at one reference point of the element (what another code's integration point reads).
  Vector6d point_stress(int e, const Eigen::Vector3d& xi, const Eigen::VectorXd& element_displacement, const StressProfile* profile,
                        const PartShape& shape) const;

  std::size_t distinct_shapes() const { return cache_.size(); }

 private:
  Eigen::MatrixXd compute_stiffness(const Eigen::Matrix3Xd& X) const;
  static void strain_matrix(const Eigen::MatrixX3d& dNdx, Eigen::MatrixXd& B);
  // C eps(u_e) + sigma_R at reference point xi of the element with nodes X; *det_J gets the Jacobian's determinant.
  Vector6d stress_at(const Eigen::Matrix3Xd& X, const Eigen::Vector3d& xi, const Eigen::VectorXd& ue, const StressProfile* profile,
                     const PartShape& shape, double* det_J) const;

  const Mesh& mesh_;
  Matrix6d C_;
  std::vector<QuadraturePoint> stiffness_rule_;
  std::unordered_map<std::string, std::size_t> cache_;
  std::vector<Eigen::MatrixXd> stored_;
  Eigen::MatrixXd scratch_;
};

}  // namespace drom::fem
