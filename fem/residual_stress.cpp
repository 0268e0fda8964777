#include "fem/residual_stress.hpp"

#include "support/input_error.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace drom::fem {

double legendre(int degree, double s) {
  if (degree == 0) return 1.0;
  double p0 = 1.0, p1 = s;
  for (int k = 2; k <= degree; ++k) {
    const double p2 = ((2.0 * k - 1.0) * s * p1 - (k - 1.0) * p0) / k;
    p0 = p1;
    p1 = p2;
  }
  return p1;
}

std::vector<int> legendre_degrees(ProfileParity parity, int max_degree) {
  std::vector<int> degrees;
  for (int j = 2; j <= max_degree; ++j) {
    if (parity == ProfileParity::Even && j % 2 != 0) continue;
    if (parity == ProfileParity::Odd && j % 2 == 0) continue;
    degrees.push_back(j);
  }
  return degrees;
}

Eigen::Vector2d StressProfile::evaluate(double s) const {
  Eigen::Vector2d sigma = Eigen::Vector2d::Zero();
  for (std::size_t k = 0; k < degrees.size(); ++k) {
    const double p = legendre(degrees[k], s);
    sigma[0] += sigma11[k] * p;
    sigma[1] += sigma22[k] * p;
  }
  return sigma;
}

Eigen::Matrix3d StressProfile::tensor(const PartShape& shape, const Eigen::Vector3d& x) const {
  const Eigen::Vector2d sigma = evaluate(shape.reduced_thickness(x));
  const Eigen::Matrix3d frame = shape.local_frame(x);
  return sigma[0] * frame.col(0) * frame.col(0).transpose() + sigma[1] * frame.col(1) * frame.col(1).transpose();
}

int StressProfile::max_degree() const { return degrees.empty() ? 0 : *std::max_element(degrees.begin(), degrees.end()); }

std::vector<StressProfile> unit_profiles(const std::vector<int>& degrees) {
  std::vector<StressProfile> units;
  for (int direction = 0; direction < 2; ++direction)
    for (std::size_t k = 0; k < degrees.size(); ++k) {
      StressProfile p{degrees, std::vector<double>(degrees.size(), 0.0), std::vector<double>(degrees.size(), 0.0)};
      (direction == 0 ? p.sigma11 : p.sigma22)[k] = 1.0;
      units.push_back(p);
    }
  return units;
}

Eigen::VectorXd profile_weights(const StressProfile& profile) {
  const auto n = static_cast<Eigen::Index>(profile.degrees.size());
  Eigen::VectorXd w(2 * n);
  for (Eigen::Index k = 0; k < n; ++k) {
    w[k] = profile.sigma11[static_cast<std::size_t>(k)];
    w[n + k] = profile.sigma22[static_cast<std::size_t>(k)];
  }
  return w;
}

ProfileTable read_profile_table(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open stress profile table");
  ProfileTable table;
  table.origin = path.string();
  std::string line;
  int line_no = 0;
  bool header_seen = false;
  while (std::getline(in, line)) {
    ++line_no;
    if (line.empty() || line[0] == '#') continue;
    if (!header_seen) {
      header_seen = true;
      std::string compact;
      for (char c : line)
        if (!std::isspace(static_cast<unsigned char>(c))) compact += c;
      if (compact != "depth,sigma11,sigma22")
        throw InputError(path.string() + ":" + std::to_string(line_no) + ": expected header 'depth,sigma11,sigma22', got '" + line + "'");
      continue;
    }
    std::stringstream ss(line);
    std::string cell;
    double values[3];
    int count = 0;
    while (std::getline(ss, cell, ',')) {
      if (count == 3) throw InputError(path.string() + ":" + std::to_string(line_no) + ": more than three columns");
      try {
        std::size_t used = 0;
        values[count] = std::stod(cell, &used);
        if (cell.find_first_not_of(" \t\r", used) != std::string::npos) throw std::invalid_argument("trailing");
      } catch (const std::exception&) {
        throw InputError(path.string() + ":" + std::to_string(line_no) + ": column " + std::to_string(count + 1) + " is not a number: '" + cell + "'");
      }
      if (!std::isfinite(values[count]))
        throw InputError(path.string() + ":" + std::to_string(line_no) + ": column " + std::to_string(count + 1) + " is not finite");
      // 10 GPa: beyond any residual stress (and any depth) in a part drom machines; a corrupted value.
      if (std::abs(values[count]) > 1e4)
        throw InputError(path.string() + ":" + std::to_string(line_no) + ": column " + std::to_string(count + 1) + " is " + cell + ", beyond any " +
                         (count == 0 ? "depth (mm)" : "stress (MPa)") + " (|value| <= 1e4)");
      ++count;
    }
    if (count != 3) throw InputError(path.string() + ":" + std::to_string(line_no) + ": expected 3 columns (depth, sigma11, sigma22), got " + std::to_string(count));
    table.depth.push_back(values[0]);
    table.sigma11.push_back(values[1]);
    table.sigma22.push_back(values[2]);
  }
  if (table.depth.empty()) throw InputError(path.string() + ": no data rows");
  return table;
}

StressProfile fit_profile(const ProfileTable& table, double thickness, const std::vector<int>& degrees) {
  const auto rows = static_cast<Eigen::Index>(table.depth.size());
  const auto cols = static_cast<Eigen::Index>(degrees.size());
  const std::string where = (table.origin.empty() ? std::string("stress profile table") : table.origin) + ": ";
  if (rows < cols)
    throw InputError(where + std::to_string(rows) + " rows cannot determine " + std::to_string(cols) + " Legendre coefficients");
  Eigen::MatrixXd A(rows, cols);
  Eigen::MatrixXd b(rows, 2);
  for (Eigen::Index i = 0; i < rows; ++i) {
    const double depth = table.depth[static_cast<std::size_t>(i)];
    if (depth < 0 || depth > thickness)
      throw InputError(where + "depth " + std::to_string(depth) + " mm lies outside the thickness [0, " + std::to_string(thickness) + "]");
    const double s = 1.0 - 2.0 * depth / thickness;  // depth is measured from the top face
    for (Eigen::Index k = 0; k < cols; ++k) A(i, k) = legendre(degrees[static_cast<std::size_t>(k)], s);
    b(i, 0) = table.sigma11[static_cast<std::size_t>(i)];
    b(i, 1) = table.sigma22[static_cast<std::size_t>(i)];
  }
  // Repeated depths determine fewer coefficients than rows: the fit would then be one of many.
  const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(A);
  if (qr.rank() < cols)
    throw InputError(where + "its depths determine only " + std::to_string(qr.rank()) + " of the " + std::to_string(cols) +
                     " Legendre coefficients: give at least as many distinct depths");
  const Eigen::MatrixXd coeffs = qr.solve(b);
  StressProfile p{degrees, {}, {}};
  for (Eigen::Index k = 0; k < cols; ++k) {
    p.sigma11.push_back(coeffs(k, 0));
    p.sigma22.push_back(coeffs(k, 1));
  }
  return p;
}

}  // namespace drom::fem
