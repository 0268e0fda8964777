#pragma once
// Biaxial residual-stress profiles through the thickness in a Legendre basis (docs/design.md §1):
// sigma_R = sigma11(s) e1(x)e1 + sigma22(s) e2(x)e2, sigma_ii(s) = sum_j a_ij P_j(s), j >= 2.
#include "geometry/part_shape.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

namespace drom::fem {

using geometry::PartShape;

double legendre(int degree, double s);

enum class ProfileParity { Even, Odd, All };

// Degrees of the basis up to max_degree: even (2, 4, ...), odd (3, 5, ...) or all (2, 3, ...).
// P_0 and P_1 are excluded: they would break force and moment equilibrium through the thickness.
std::vector<int> legendre_degrees(ProfileParity parity, int max_degree);

struct StressProfile {
  std::vector<int> degrees;
  std::vector<double> sigma11;  // MPa, one coefficient per degree
  std::vector<double> sigma22;

  // Local-frame stresses (sigma11, sigma22) at reduced thickness s.
  Eigen::Vector2d evaluate(double s) const;
  // Cartesian stress tensor at x on the given part.
  Eigen::Matrix3d tensor(const PartShape& shape, const Eigen::Vector3d& x) const;
  int max_degree() const;
};

// One profile per (direction, degree) with a single unit coefficient: sigma11 degrees first, then sigma22.
// Any profile is the combination of these with weights profile_weights().
std::vector<StressProfile> unit_profiles(const std::vector<int>& degrees);
Eigen::VectorXd profile_weights(const StressProfile& profile);

// A measured profile: depth below the top face (mm) and the two principal stresses (MPa).
struct ProfileTable {
  std::vector<double> depth, sigma11, sigma22;
  std::string origin;  // the file, for messages
};
// CSV with header "depth,sigma11,sigma22"; errors name the file and line.
ProfileTable read_profile_table(const std::filesystem::path& path);
// Least-squares fit in the given Legendre degrees (their span drops the non-equilibrated P_0, P_1 part).
StressProfile fit_profile(const ProfileTable& table, double thickness, const std::vector<int>& degrees);

}  // namespace drom::fem
