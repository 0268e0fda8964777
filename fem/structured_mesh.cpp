#include "fem/structured_mesh.hpp"

#include "fem/shape_functions.hpp"

#include <cmath>
#include <stdexcept>

namespace drom::fem {

std::vector<double> thickness_levels(double thickness, int nt, double grading) {
  if (nt < 1 || grading <= 0) throw std::invalid_argument("thickness_levels: nt >= 1 and grading > 0");
  // Element k (from the bottom) has size proportional to ratio^k with ratio^(nt-1) = 1 / grading.
  const double ratio = nt > 1 ? std::pow(1.0 / grading, 1.0 / (nt - 1)) : 1.0;
  std::vector<double> sizes(static_cast<std::size_t>(nt));
  double total = 0;
  for (int k = 0; k < nt; ++k) total += sizes[static_cast<std::size_t>(k)] = std::pow(ratio, k);
  std::vector<double> levels{0.0};
  for (double s : sizes) levels.push_back(levels.back() + s * thickness / total);
  levels.back() = thickness;
  return levels;
}

Mesh make_structured_hex_mesh(const PartShape& shape, const StructuredMeshSpec& spec) {
  if (!is_hex(spec.element)) throw std::invalid_argument("structured mesh: hexahedral elements only");
  if (spec.nu < 1 || spec.nv < 1 || spec.nt < 1) throw std::invalid_argument("structured mesh: need at least one element per direction");
  const int Lu = 2 * spec.nu + 1, Lv = 2 * spec.nv + 1, Lt = 2 * spec.nt + 1;  // lattice sizes
  const auto levels = thickness_levels(shape.thickness(), spec.nt, spec.thickness_grading);
  auto lattice_t = [&](int k) {
    const auto lo = static_cast<std::size_t>(k / 2);
    return k % 2 == 0 ? levels[lo] : 0.5 * (levels[lo] + levels[lo + 1]);
  };

  Mesh mesh;
  mesh.type = spec.element;
  // Hex20 uses lattice points with at most one odd index (no face or body centres).
  const int max_odd = spec.element == ElementType::Hex20 ? 1 : 3;
  std::vector<int> id(static_cast<std::size_t>(Lu) * Lv * Lt, -1);
  auto at = [&](int i, int j, int k) -> int& { return id[(static_cast<std::size_t>(k) * Lv + j) * Lu + i]; };
  for (int k = 0; k < Lt; ++k)
    for (int j = 0; j < Lv; ++j)
      for (int i = 0; i < Lu; ++i) {
        if ((i % 2) + (j % 2) + (k % 2) > max_odd) continue;
        at(i, j, k) = mesh.node_count();
        const Eigen::Vector3d p(shape.length_u() * i / (Lu - 1), shape.length_v() * j / (Lv - 1), lattice_t(k));
        mesh.nodes.push_back(shape.from_parametric(p));
      }

  const Eigen::MatrixX3d ref = reference_nodes(spec.element);
  const int per_element = nodes_per_element(spec.element);
  mesh.connectivity.reserve(static_cast<std::size_t>(spec.nu) * spec.nv * spec.nt * per_element);
  for (int ek = 0; ek < spec.nt; ++ek)
    for (int ej = 0; ej < spec.nv; ++ej)
      for (int ei = 0; ei < spec.nu; ++ei)
        for (int a = 0; a < per_element; ++a)
          mesh.connectivity.push_back(at(2 * ei + 1 + static_cast<int>(ref(a, 0)), 2 * ej + 1 + static_cast<int>(ref(a, 1)),
                                         2 * ek + 1 + static_cast<int>(ref(a, 2))));
  return mesh;
}

}  // namespace drom::fem
