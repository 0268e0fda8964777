#include "pgd/tensor_grid.hpp"

#include "fem/structured_mesh.hpp"

#include <algorithm>
#include <stdexcept>

namespace drom::pgd {

TensorGrid TensorGrid::make(const PartShape& shape, int nu, int nv, int nt, double thickness_grading) {
  if (shape.kind() == PartShape::Kind::Block) throw std::invalid_argument("PGD tensor grid: a plate or a panel, not a block");
  if (nu < 1 || nv < 1 || nt < 1) throw std::invalid_argument("PGD tensor grid: at least one element per direction");
  TensorGrid g;
  g.shape = shape;
  g.nu = nu;
  g.nv = nv;
  g.nt = nt;
  g.grading = thickness_grading;
  g.levels = fem::thickness_levels(shape.thickness(), nt, thickness_grading);
  return g;
}

double TensorGrid::t(int k) const {
  const auto lo = static_cast<std::size_t>(k / 2);
  return k % 2 == 0 ? levels[lo] : 0.5 * (levels[lo] + levels[lo + 1]);
}

std::array<int, 9> TensorGrid::plane_element_nodes(int e) const {
  const int ei = e % nu, ej = e / nu;
  std::array<int, 9> n{};
  for (int b = 0; b < 3; ++b)
    for (int a = 0; a < 3; ++a) n[static_cast<std::size_t>(a + 3 * b)] = (2 * ej + b) * lattice_u() + 2 * ei + a;
  return n;
}

double TensorGrid::smallest_element_size() const {
  double h = std::min(element_size_u(), element_size_v());
  for (int k = 0; k < nt; ++k) h = std::min(h, levels[static_cast<std::size_t>(k + 1)] - levels[static_cast<std::size_t>(k)]);
  return h;
}

fem::Mesh TensorGrid::hex27_mesh() const {
  return fem::make_structured_hex_mesh(shape, {nu, nv, nt, grading, fem::ElementType::Hex27});
}

}  // namespace drom::pgd
