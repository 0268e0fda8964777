#include "fem/stiffness_pattern.hpp"

#include <algorithm>
#include <vector>

namespace drom::fem {

StiffnessPattern::StiffnessPattern(const Mesh& mesh) {
  // Node adjacency through elements, then 3x3 blocks per adjacent pair.
  std::vector<std::vector<int>> adjacent(static_cast<std::size_t>(mesh.node_count()));
  for (int e = 0; e < mesh.element_count(); ++e) {
    const auto nodes = mesh.element(e);
    for (int a : nodes)
      for (int b : nodes)
        if (a >= b) adjacent[static_cast<std::size_t>(b)].push_back(a);  // column b holds rows a >= b
  }
  const auto ndof = static_cast<Eigen::Index>(3 * mesh.node_count());
  std::vector<Eigen::Index> outer(static_cast<std::size_t>(ndof) + 1, 0);
  std::vector<int> inner;
  for (std::size_t b = 0; b < adjacent.size(); ++b) {
    auto& rows = adjacent[b];
    std::sort(rows.begin(), rows.end());
    rows.erase(std::unique(rows.begin(), rows.end()), rows.end());
    for (int cb = 0; cb < 3; ++cb) {
      const auto col = static_cast<int>(3 * b) + cb;
      for (int a : rows)
        for (int ca = 0; ca < 3; ++ca) {
          const int row = 3 * a + ca;
          if (row >= col) inner.push_back(row);
        }
      outer[static_cast<std::size_t>(col) + 1] = static_cast<Eigen::Index>(inner.size());
    }
    rows.clear();
    rows.shrink_to_fit();
  }
  pattern_.resize(ndof, ndof);
  pattern_.resizeNonZeros(static_cast<Eigen::Index>(inner.size()));
  std::copy(inner.begin(), inner.end(), pattern_.innerIndexPtr());
  for (std::size_t c = 0; c < outer.size(); ++c) pattern_.outerIndexPtr()[c] = static_cast<int>(outer[c]);
  std::fill(pattern_.valuePtr(), pattern_.valuePtr() + inner.size(), 0.0);
}

void StiffnessPattern::add_element(Eigen::SparseMatrix<double>& K, std::span<const int> nodes, const Eigen::MatrixXd& Ke, double scale) const {
  const int* outer = K.outerIndexPtr();
  const int* inner = K.innerIndexPtr();
  double* values = K.valuePtr();
  const auto n = static_cast<int>(nodes.size());
  // A column holds whole 3 x 3 node blocks (clipped at the diagonal): one search per node pair,
  // the node's three rows follow one another.
  for (int q = 0; q < 3 * n; ++q) {
    const int col = 3 * nodes[static_cast<std::size_t>(q / 3)] + q % 3;
    const int* begin = inner + outer[col];
    const int* end = inner + outer[col + 1];
    for (int a = 0; a < n; ++a) {
      const int first_row = 3 * nodes[static_cast<std::size_t>(a)];
      if (first_row + 2 < col) continue;
      const int c0 = std::max(0, col - first_row);
      const int* it = std::lower_bound(begin, end, first_row + c0);
      double* v = values + (it - inner);
      for (int c = c0; c < 3; ++c) v[c - c0] += scale * Ke(3 * a + c, q);
    }
  }
}

}  // namespace drom::fem
