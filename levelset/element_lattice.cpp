#include "levelset/element_lattice.hpp"

#include "levelset/cut_fraction.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace drom::levelset {

struct ElementLattices::Lattice {
  Eigen::Matrix3Xd xi;                        // reference points
  Eigen::MatrixXd shape;                      // shape functions at xi (nodes x points)
  std::vector<std::array<int, 4>> simplices;  // lattice points of each tetrahedron; all have one reference volume
};

namespace {

// The six tetrahedra of a cube that share its diagonal from the base corner (Kuhn's triangulation):
// one per order in which the three coordinates step from 0 to 1.
constexpr std::array<std::array<int, 3>, 6> kKuhnOrders = {{{0, 1, 2}, {0, 2, 1}, {1, 0, 2}, {1, 2, 0}, {2, 0, 1}, {2, 1, 0}}};

// Beyond these the lattice is coarser than asked (an element 256 spacings long), and curved cuts in it
// are integrated at that coarser spacing.
constexpr int kMaxHexCells = 256, kMaxTetCells = 128;

// Hexahedra: {-1, 0, 1}^3, point (i, j, k) at (i + 1) + 3 (j + 1) + 9 (k + 1). Tetrahedra: the corners
// and the edge midpoints. A quadratic map is affine when it is affine on these points.
const Eigen::Matrix3Xd& probe_points(bool hex) {
  static const Eigen::Matrix3Xd cube = [] {
    Eigen::Matrix3Xd p(3, 27);
    for (int k = -1; k <= 1; ++k)
      for (int j = -1; j <= 1; ++j)
        for (int i = -1; i <= 1; ++i) p.col((i + 1) + 3 * (j + 1) + 9 * (k + 1)) = Eigen::Vector3d(i, j, k);
    return p;
  }();
  static const Eigen::Matrix3Xd tetrahedron = [] {
    Eigen::Matrix3Xd p(3, 10);
    p << 0, 1, 0, 0, .5, .5, 0, 0, .5, 0,  //
        0, 0, 1, 0, 0, .5, .5, 0, 0, .5,   //
        0, 0, 0, 1, 0, 0, 0, .5, .5, .5;
    return p;
  }();
  return hex ? cube : tetrahedron;
}

}  // namespace

ElementLattices::ElementLattices() = default;
ElementLattices::~ElementLattices() = default;

const Eigen::MatrixXd& ElementLattices::probe_shape(const geometry::ElementGeometry& elements, int node_count) const {
  const bool hex = elements.reference_cell() == geometry::ReferenceCell::Hexahedron;
  std::lock_guard<std::mutex> lock(mutex_);
  auto [it, added] = probe_shapes_.try_emplace({hex ? 0 : 1, node_count});
  if (added) it->second = elements.shape_values(probe_points(hex));
  return it->second;  // map nodes never move
}

std::shared_ptr<const ElementLattices::Lattice> ElementLattices::lattice(const geometry::ElementGeometry& elements, int node_count,
                                                                         const std::array<int, 3>& n) const {
  const bool hex = elements.reference_cell() == geometry::ReferenceCell::Hexahedron;
  const std::array<int, 5> key{hex ? 0 : 1, node_count, n[0], n[1], n[2]};
  std::lock_guard<std::mutex> lock(mutex_);
  if (auto it = lattices_.find(key); it != lattices_.end()) return it->second;
  auto made = std::make_shared<Lattice>();
  std::vector<Eigen::Vector3d> xi;
  auto add_simplex = [&](std::array<int, 3> at, const std::array<int, 3>& order, auto&& index) {
    std::array<int, 4> simplex{};
    simplex[0] = index(at[0], at[1], at[2]);
    for (std::size_t step = 0; step < 3; ++step) {
      ++at[static_cast<std::size_t>(order[step])];
      simplex[step + 1] = index(at[0], at[1], at[2]);
    }
    made->simplices.push_back(simplex);
  };
  if (hex) {
    // Points (i, j, k) of an n0 x n1 x n2 grid over [-1, 1]^3, every cell in its six Kuhn tetrahedra.
    auto index = [&](int i, int j, int k) { return i + (n[0] + 1) * (j + (n[1] + 1) * k); };
    for (int k = 0; k <= n[2]; ++k)
      for (int j = 0; j <= n[1]; ++j)
        for (int i = 0; i <= n[0]; ++i) xi.emplace_back(-1 + 2.0 * i / n[0], -1 + 2.0 * j / n[1], -1 + 2.0 * k / n[2]);
    for (int k = 0; k < n[2]; ++k)
      for (int j = 0; j < n[1]; ++j)
        for (int i = 0; i < n[0]; ++i)
          for (const auto& order : kKuhnOrders) add_simplex({i, j, k}, order, index);
  } else {
    // The unit tetrahedron, in the coordinates y = (xi1 + xi2 + xi3, xi2 + xi3, xi3) (a map of unit
    // determinant), is the ordered set k >= y1 >= y2 >= y3 >= 0 (in units of 1/k). Kuhn's triangulation
    // of the unit cubes tiles it exactly: in a cube whose base has equal coordinates, only the
    // tetrahedra that keep the order.
    const int k = n[0];
    std::vector<int> slots(static_cast<std::size_t>((k + 1) * (k + 1) * (k + 1)), -1);
    auto index = [&](int a, int b, int c) -> int& { return slots[static_cast<std::size_t>((a * (k + 1) + b) * (k + 1) + c)]; };
    for (int a = 0; a <= k; ++a)
      for (int b = 0; b <= a; ++b)
        for (int c = 0; c <= b; ++c) {
          index(a, b, c) = static_cast<int>(xi.size());
          xi.emplace_back(static_cast<double>(a - b) / k, static_cast<double>(b - c) / k, static_cast<double>(c) / k);
        }
    for (int a = 0; a < k; ++a)
      for (int b = 0; b <= a; ++b)
        for (int c = 0; c <= b; ++c)
          for (const auto& order : kKuhnOrders) {
            std::array<int, 3> position{};
            for (int step = 0; step < 3; ++step) position[static_cast<std::size_t>(order[static_cast<std::size_t>(step)])] = step;
            if ((a == b && position[0] > position[1]) || (b == c && position[1] > position[2])) continue;
            add_simplex({a, b, c}, order, index);
          }
  }
  made->xi.resize(3, static_cast<Eigen::Index>(xi.size()));
  for (std::size_t p = 0; p < xi.size(); ++p) made->xi.col(static_cast<Eigen::Index>(p)) = xi[p];
  made->shape = elements.shape_values(made->xi);
  lattices_.emplace(key, made);
  return made;
}

double ElementLattices::negative_share(const geometry::ElementGeometry& elements, std::size_t e, double spacing, const Field& field) const {
  const bool hex = elements.reference_cell() == geometry::ReferenceCell::Hexahedron;
  const Eigen::Matrix3Xd X = elements.nodes(e);
  const int node_count = static_cast<int>(X.cols());
  const Eigen::Matrix3Xd probes = X * probe_shape(elements, node_count);
  // The element's affine part (origin and Jacobian at the reference origin), and whether it is all.
  Eigen::Vector3d origin;
  Eigen::Matrix3d J;
  if (hex) {
    origin = probes.col(13);
    for (int d = 0; d < 3; ++d) {
      const int step = d == 0 ? 1 : (d == 1 ? 3 : 9);
      J.col(d) = 0.5 * (probes.col(13 + step) - probes.col(13 - step));
    }
  } else {
    origin = probes.col(0);
    for (int d = 0; d < 3; ++d) J.col(d) = probes.col(d + 1) - origin;
  }
  const Eigen::Matrix3Xd& reference = probe_points(hex);
  const double deviation = ((J * reference).colwise() + origin - probes).colwise().norm().maxCoeff();
  const bool affine = deviation <= 1e-10 * J.norm();

  std::array<int, 3> cells{1, 1, 1};
  if (hex) {
    for (int d = 0; d < 3; ++d)
      cells[static_cast<std::size_t>(d)] = std::clamp(static_cast<int>(std::ceil(2 * J.col(d).norm() / spacing)), 1, kMaxHexCells);
  } else {
    double longest = std::max({J.col(0).norm(), J.col(1).norm(), J.col(2).norm()});
    for (int a = 0; a < 3; ++a)
      for (int b = a + 1; b < 3; ++b) longest = std::max(longest, (J.col(a) - J.col(b)).norm());
    cells[0] = std::clamp(static_cast<int>(std::ceil(longest / spacing)), 1, kMaxTetCells);
  }
  const auto grid = lattice(elements, node_count, cells);
  // An affine element's tetrahedra all have the same volume; others are weighed by their own.
  const Eigen::Matrix3Xd x = affine ? Eigen::Matrix3Xd((J * grid->xi).colwise() + origin) : Eigen::Matrix3Xd(X * grid->shape);
  std::vector<double> values(static_cast<std::size_t>(x.cols()));
  for (Eigen::Index p = 0; p < x.cols(); ++p) values[static_cast<std::size_t>(p)] = field.estimate(x.col(p));
  for (std::size_t p = 0; p < values.size(); ++p)
    if (std::abs(values[p]) <= field.trust) values[p] = field.exact(x.col(static_cast<Eigen::Index>(p)));
  const double flat = 1e-9 * spacing;
  double gone = 0, total = 0;
  std::size_t wholly_in = 0, wholly_out = 0;
  for (const auto& s : grid->simplices) {
    const double f0 = values[static_cast<std::size_t>(s[0])], f1 = values[static_cast<std::size_t>(s[1])],
                 f2 = values[static_cast<std::size_t>(s[2])], f3 = values[static_cast<std::size_t>(s[3])];
    double share;
    if (std::abs(f0) < flat && std::abs(f1) < flat && std::abs(f2) < flat && std::abs(f3) < flat) {
      // All four corners on the surface: the tetrahedron spans an edge of the region (a floor meeting
      // a wall, a cut meeting the stock's face), where the interpolant vanishes identically. Its
      // inside lies on one side of the edge, which its centroid tells.
      share = field.exact(0.25 * (x.col(s[0]) + x.col(s[1]) + x.col(s[2]) + x.col(s[3]))) < 0 ? 1.0 : 0.0;
    } else if (f0 >= 0 && f1 >= 0 && f2 >= 0 && f3 >= 0) {
      share = 0;
    } else if (f0 < 0 && f1 < 0 && f2 < 0 && f3 < 0) {
      share = 1;
    } else {
      share = negative_fraction(f0, f1, f2, f3);
    }
    wholly_in += share == 1 ? 1 : 0;
    wholly_out += share == 0 ? 1 : 0;
    if (affine) {
      gone += share;
      continue;
    }
    const Eigen::Vector3d x0 = x.col(s[0]);
    const double volume = std::abs((x.col(s[1]) - x0).dot((x.col(s[2]) - x0).cross(x.col(s[3]) - x0)));
    gone += share * volume;
    total += volume;
  }
  // Wholly one side: exactly 0 or 1, whatever the rounding of the volumes' sum.
  if (wholly_in == grid->simplices.size()) return 1.0;
  if (wholly_out == grid->simplices.size()) return 0.0;
  if (affine) return gone / static_cast<double>(grid->simplices.size());
  return total > 0 ? gone / total : 0.0;
}

}  // namespace drom::levelset
