#pragma once
// Uniform removal of a top layer: the element activity it leaves, the closed-form distortion of
// the free remaining plate (the FE core's reference, issue 2 check 3), and the curvature measured
// on an FE displacement field.
#include "fem/mesh.hpp"
#include "geometry/element_geometry.hpp"
#include "geometry/part_shape.hpp"
#include "fem/residual_stress.hpp"

#include <Eigen/Core>

#include <vector>

namespace drom::fem {

using geometry::RemovalCriterion;

// Remaining volume fraction of each element after removing everything with t > thickness - depth.
// Centroid: 0 or 1 by the element centroid (the seed's criterion). VolumeFraction: by sub-cell
// sampling with a 6-point-per-direction rule (exact when the cut plane is an element face).
std::vector<double> layer_activity(const Mesh& mesh, const PartShape& shape, double depth, RemovalCriterion criterion);

struct PlateDistortion {
  Eigen::Vector2d membrane_strain;  // eps_xx, eps_yy at mid-thickness
  Eigen::Vector2d curvature;        // kappa_x, kappa_y (1/mm); eps(z) = eps + kappa (z - h/2)
};

// Free plate of thickness e whose top layer of depth d was removed, carrying the profile sigma(z):
// eps = -A^-1 N and kappa = -D^-1 M with N, M the profile's resultants over the remaining h = e - d.
PlateDistortion layer_removal_closed_form(const StressProfile& profile, double thickness, double depth, double young_modulus,
                                          double poisson_ratio);

// Least-squares fit of w = c0 + c1 x + c2 y + c3 x^2 + c4 xy + c5 y^2 over the given nodes; returns
// (kappa_x, kappa_y) = (-2 c3, -2 c5).
Eigen::Vector2d fit_plate_curvature(const Mesh& mesh, const std::vector<int>& nodes, const Eigen::VectorXd& u);

}  // namespace drom::fem
