#pragma once
// The PCA plane of a surface or zone (Herraz ch. 2): the covariance of its sample points (cell
// centres, unweighted, divided by n) gives the principal directions and the fitted rectangle, the
// shape factor mu = sqrt(lambda_I / lambda_II), the size chi = 12 sqrt(lambda_I lambda_II) and the
// plane's slope; its normals give the mean local slope and steepest direction. Angles in radians;
// azimuths are measured from X in the XY plane and reduced modulo pi to [-pi/2, pi/2).
#include <Eigen/Core>

#include <vector>

namespace drom::paths {

struct PcaPlane {
  int count = 0;                  // sample points
  Eigen::Vector3d mean = Eigen::Vector3d::Zero();
  Eigen::Vector3d lambda = Eigen::Vector3d::Zero();  // lambda_I >= lambda_II >= lambda_III, mm^2
  Eigen::Matrix3d axes = Eigen::Matrix3d::Identity();  // columns X_I, X_II, X_III = X_I x X_II, X_III . Z >= 0
  double shape_factor = 1;        // mu~ (eq. 2.13)
  double size = 0;                // chi~, mm^2 (eq. 2.14)
  double width = 0, height = 0;   // the fitted rectangle: sqrt(12 lambda_I) along X_I, sqrt(12 lambda_II) along X_II
  double slope = 0;               // s~ = arccos |X_III . Z| (eq. 2.16 as corrected in the digest)
  double principal_azimuth = 0;   // of X_I
  double steepest_azimuth = 0;    // of X_III's XY projection (the plane's steepest slope)
  // Unit steepest-slope direction in the plane (uphill), zero on a level plane.
  Eigen::Vector3d steepest_direction = Eigen::Vector3d::Zero();
};

// Needs at least 3 points; throws std::invalid_argument otherwise.
PcaPlane pca_plane(const std::vector<Eigen::Vector3d>& points);
// From a covariance matrix (1/n) and mean already accumulated (a zone's running covariance).
PcaPlane pca_plane(const Eigen::Matrix3d& covariance, const Eigen::Vector3d& mean, int count);

// The mean of local slopes arccos |n . Z| (eq. 2.15).
double mean_slope(const std::vector<Eigen::Vector3d>& normals);
// The mean steepest-slope azimuth: the axial mean (directions taken modulo pi, through the doubled
// angle), weighted by each normal's horizontal part so level points do not vote.
double mean_steepest_azimuth(const std::vector<Eigen::Vector3d>& normals);

// An azimuth reduced modulo pi to [-pi/2, pi/2).
double reduce_azimuth(double angle);

}  // namespace drom::paths
