#include "reduce/deviation_family.hpp"

#include "support/input_error.hpp"

#include <nanoflann.hpp>

#include <algorithm>
#include <cstdint>
#include <cmath>
#include <fstream>
#include <sstream>

namespace drom::reduce {

namespace {

// The measured points seen by nanoflann in the plane: distances in (x, y) only.
struct MeasuredPointsXY {
  const std::vector<Eigen::Vector3d>& points;
  std::size_t kdtree_get_point_count() const { return points.size(); }
  double kdtree_get_pt(std::size_t i, std::size_t d) const { return points[i][static_cast<Eigen::Index>(d)]; }
  template <class Box>
  bool kdtree_get_bbox(Box&) const {
    return false;
  }
};
using MeasuredTree = nanoflann::KDTreeSingleIndexAdaptor<nanoflann::L2_Simple_Adaptor<double, MeasuredPointsXY>, MeasuredPointsXY, 2, std::uint32_t>;

}  // namespace

std::array<std::pair<int, double>, 4> DeviationGrid::weights(double x, double y) const {
  const double u = std::clamp((x - x0) / (x1 - x0) * (nx - 1), 0.0, static_cast<double>(nx - 1));
  const double v = std::clamp((y - y0) / (y1 - y0) * (ny - 1), 0.0, static_cast<double>(ny - 1));
  const int i = std::min(static_cast<int>(u), nx - 2), j = std::min(static_cast<int>(v), ny - 2);
  const double a = u - i, b = v - j;
  return {{{index(i, j), (1 - a) * (1 - b)}, {index(i + 1, j), a * (1 - b)}, {index(i, j + 1), (1 - a) * b}, {index(i + 1, j + 1), a * b}}};
}

std::vector<double> DeviationRange::values() const {
  std::vector<double> v;
  for (int k = 0; k < count; ++k) v.push_back(count == 1 ? min : min + (max - min) * k / (count - 1));
  return v;
}

double seed_parametric_surface(double x, double y, double a, double b) {
  const double u = x / 100 - a;
  return std::exp(-u * u / b) + 2 * (0.76 - y / 100) * (0.14 - x / 100);
}

double seed_true_surface(double x, double y) {
  const double u = x / 100 - 0.42;
  return 4 * std::exp(-u * u / 0.2) + 2 * (0.76 - y / 100) * (0.14 - x / 100);
}

void DeviationFamily::add(const std::string& label, const Eigen::VectorXd& values) {
  if (values.size() != grid_.size()) throw std::invalid_argument("deviation family: a member needs one value per grid point");
  snapshots_.conservativeResize(grid_.size(), snapshots_.cols() + 1);
  snapshots_.col(snapshots_.cols() - 1) = values;
  labels_.push_back(label);
}

namespace {
template <class F>
Eigen::VectorXd sample(const DeviationGrid& g, F f) {
  Eigen::VectorXd v(g.size());
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) v[g.index(i, j)] = f(g.x(i), g.y(j));
  return v;
}
}  // namespace

void DeviationFamily::add_bending(char axis, const DeviationRange& radius, bool both_signs) {
  const double xc = 0.5 * (grid_.x0 + grid_.x1), yc = 0.5 * (grid_.y0 + grid_.y1);
  for (double R : radius.values())
    for (double sign : both_signs ? std::vector<double>{1, -1} : std::vector<double>{1}) {
      add(std::string("bending_") + axis + "_R" + std::to_string(static_cast<long>(R)) + (sign > 0 ? "+" : "-"), sample(grid_, [&](double x, double y) {
            const double s = axis == 'x' ? y - yc : x - xc;
            return sign * s * s / (2 * R);
          }));
    }
}

void DeviationFamily::add_twist(const DeviationRange& rate) {
  const double xc = 0.5 * (grid_.x0 + grid_.x1), yc = 0.5 * (grid_.y0 + grid_.y1);
  for (double k : rate.values()) add("twist_" + std::to_string(k), sample(grid_, [&](double x, double y) { return k * (x - xc) * (y - yc); }));
}

void DeviationFamily::add_offset(const DeviationRange& tz) {
  for (double t : tz.values()) add("offset_" + std::to_string(t), sample(grid_, [&](double, double) { return t; }));
}

void DeviationFamily::add_tilt(char axis, const DeviationRange& angle) {
  const double xc = 0.5 * (grid_.x0 + grid_.x1), yc = 0.5 * (grid_.y0 + grid_.y1);
  for (double r : angle.values())
    add(std::string("tilt_") + axis + "_" + std::to_string(r), sample(grid_, [&](double x, double y) { return axis == 'x' ? r * (y - yc) : -r * (x - xc); }));
}

void DeviationFamily::add_seed_parametric(const DeviationRange& a, const DeviationRange& b) {
  for (double av : a.values())
    for (double bv : b.values())
      add("seed_a" + std::to_string(av) + "_b" + std::to_string(bv), sample(grid_, [&](double x, double y) { return seed_parametric_surface(x, y, av, bv); }));
}

void DeviationFamily::add_measured(const std::filesystem::path& csv, double nominal_z) {
  std::ifstream in(csv);
  if (!in) throw InputError(csv.string() + ": cannot open the measured surface");
  std::vector<Eigen::Vector3d> pts;
  std::string line;
  for (int n = 1; std::getline(in, line); ++n) {
    if (line.empty() || line[0] == '#') continue;
    std::replace(line.begin(), line.end(), ',', ' ');
    std::istringstream ss(line);
    double x, y, z;
    if (!(ss >> x >> y >> z)) {
      if (n == 1) continue;  // a header
      throw InputError(csv.string() + ":" + std::to_string(n) + ": expected three numbers x,y,z");
    }
    if (!std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z)) throw InputError(csv.string() + ":" + std::to_string(n) + ": x, y and z must be finite");
    // A kilometre: beyond any blank (squared distances of such points would overflow).
    if (std::abs(x) > 1e6 || std::abs(y) > 1e6 || std::abs(z - nominal_z) > 1e6)
      throw InputError(csv.string() + ":" + std::to_string(n) + ": x, y and z must lie within 1e6 mm");
    pts.emplace_back(x, y, z - nominal_z);
  }
  if (pts.size() < 4) throw InputError(csv.string() + ": a measured surface needs at least 4 points, found " + std::to_string(pts.size()));
  // A laser scan of a blank has 10⁵–10⁶ points: a k-d tree over (x, y) finds each grid point's 4
  // nearest in O(log points), where scanning them all took 11 s at 10⁶ points on a 101 x 101 grid
  // (docs/benchmarks.md).
  const MeasuredPointsXY cloud{pts};
  const MeasuredTree tree(2, cloud, nanoflann::KDTreeSingleIndexAdaptorParams(16));
  add("measured_" + csv.stem().string(), sample(grid_, [&](double x, double y) {
        // Inverse-distance weights of the 4 nearest points (exact at a measured point).
        const double query[2] = {x, y};
        std::array<std::uint32_t, 4> index{};
        std::array<double, 4> d2{};
        const std::size_t found = tree.knnSearch(query, index.size(), index.data(), d2.data());
        // At a measured point: its value (the mean, where the point was measured more than once).
        if (d2[0] < 1e-18) {
          double sum = 0;
          int at = 0;
          for (std::size_t k = 0; k < found && d2[k] < 1e-18; ++k) sum += pts[index[k]].z(), ++at;
          return sum / at;
        }
        double w = 0, v = 0;
        for (std::size_t k = 0; k < found; ++k) w += 1 / d2[k], v += pts[index[k]].z() / d2[k];
        return v / w;
      }));
}

}  // namespace drom::reduce
