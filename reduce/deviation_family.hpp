#pragma once
// The blank's possible geometric deviations (docs/design.md §8, seed chapter 2): a family of surfaces on a
// grid over the area of interest, from parametric defect classes and from surfaces measured on
// earlier parts. Its POD (reduce/pod.hpp, the seed's tolerance-based truncation) gives the deviation
// modes the online identification fits laser points in.
//   - bending about x or y: z = sign (s - s_c)^2 / (2 R) for radii in a range (s = y or x);
//   - twist: z = k (x - x_c)(y - y_c);
//   - rigid offset t_z, tilts r_x (z = r_x (y - y_c)) and r_y (z = -r_y (x - x_c));
//   - the seed's parametric surface (eq. 2.20) over a grid of (a, b);
//   - measured surfaces: CSV "x,y,z" point clouds, interpolated onto the grid.
#include <Eigen/Core>

#include <array>
#include <filesystem>
#include <string>
#include <vector>

namespace drom::reduce {

struct DeviationGrid {
  double x0 = 0, x1 = 100, y0 = 0, y1 = 100;
  int nx = 101, ny = 101;
  int size() const { return nx * ny; }
  double x(int i) const { return x0 + (x1 - x0) * i / (nx - 1); }
  double y(int j) const { return y0 + (y1 - y0) * j / (ny - 1); }
  int index(int i, int j) const { return j * nx + i; }
  bool contains(double x, double y) const { return x >= x0 && x <= x1 && y >= y0 && y <= y1; }
  // Bilinear interpolation weights at (x, y) (clamped to the grid): 4 (index, weight) pairs.
  std::array<std::pair<int, double>, 4> weights(double x, double y) const;
};

struct DeviationRange {
  double min = 0, max = 0;
  int count = 0;  // values spread evenly over [min, max]; 1: min only
  std::vector<double> values() const;
};

class DeviationFamily {
 public:
  explicit DeviationFamily(DeviationGrid grid) : grid_(grid) {}
  const DeviationGrid& grid() const { return grid_; }
  const Eigen::MatrixXd& snapshots() const { return snapshots_; }  // grid points x members
  const std::vector<std::string>& labels() const { return labels_; }
  int size() const { return static_cast<int>(labels_.size()); }

  void add_bending(char axis /* 'x': curvature along y; 'y': along x */, const DeviationRange& radius, bool both_signs = true);
  void add_twist(const DeviationRange& rate);   // z = k (x - xc)(y - yc), k in 1/mm
  void add_offset(const DeviationRange& tz);
  void add_tilt(char axis, const DeviationRange& angle);  // radians (small)
  void add_seed_parametric(const DeviationRange& a, const DeviationRange& b);  // eq. 2.20
  // A measured surface: CSV lines "x,y,z" (a header line is allowed), deviation from the nominal
  // altitude, inverse-distance interpolated onto the grid from the 4 nearest points (at a point
  // measured more than once, the mean of its measurements). Throws
  // InputError naming the file and line.
  void add_measured(const std::filesystem::path& csv, double nominal_z = 0);
  void add(const std::string& label, const Eigen::VectorXd& values);

 private:
  DeviationGrid grid_;
  Eigen::MatrixXd snapshots_;
  std::vector<std::string> labels_;
};

// The seed's surfaces of §2.3 (eqs. 2.19, 2.20), in mm over [0, 100]^2.
double seed_true_surface(double x, double y);
double seed_parametric_surface(double x, double y, double a, double b);

}  // namespace drom::reduce
