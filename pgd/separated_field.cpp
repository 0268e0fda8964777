#include "pgd/separated_field.hpp"

#include <cmath>

#include "support/hdf5_writer.hpp"

#include <Eigen/Dense>

#include <algorithm>

namespace drom::pgd {

ComponentTensors zero_tensors(const TensorGrid& grid) {
  ComponentTensors r;
  for (auto& m : r) m = Eigen::MatrixXd::Zero(grid.plane_nodes(), grid.thickness_nodes());
  return r;
}

double norm(const ComponentTensors& r) {
  double s = 0;
  for (const auto& m : r) s += m.squaredNorm();
  return std::sqrt(s);
}

SeparatedField SeparatedField::empty(const TensorGrid& grid) {
  SeparatedField f;
  for (int i = 0; i < 3; ++i) {
    f.X[static_cast<std::size_t>(i)].resize(grid.plane_nodes(), 0);
    f.Z[static_cast<std::size_t>(i)].resize(grid.thickness_nodes(), 0);
  }
  return f;
}

int SeparatedField::max_terms() const { return std::max({terms(0), terms(1), terms(2)}); }

std::size_t SeparatedField::stored_values() const {
  std::size_t n = 0;
  for (std::size_t i = 0; i < 3; ++i) n += static_cast<std::size_t>(X[i].size() + Z[i].size());
  return n;
}

void SeparatedField::append(int component, const Eigen::VectorXd& x, const Eigen::VectorXd& z) {
  auto& Xi = X[static_cast<std::size_t>(component)];
  auto& Zi = Z[static_cast<std::size_t>(component)];
  Xi.conservativeResize(Eigen::NoChange, Xi.cols() + 1);
  Zi.conservativeResize(Eigen::NoChange, Zi.cols() + 1);
  Xi.rightCols(1) = x;
  Zi.rightCols(1) = z;
}

void SeparatedField::append(const SeparatedField& other, double scale) {
  for (std::size_t i = 0; i < 3; ++i) {
    const auto q = X[i].cols(), extra = other.X[i].cols();
    X[i].conservativeResize(other.X[i].rows(), q + extra);
    Z[i].conservativeResize(other.Z[i].rows(), q + extra);
    X[i].rightCols(extra) = scale * other.X[i];
    Z[i].rightCols(extra) = other.Z[i];
  }
}

Eigen::MatrixXd SeparatedField::component(int i) const {
  return X[static_cast<std::size_t>(i)] * Z[static_cast<std::size_t>(i)].transpose();
}

ComponentTensors SeparatedField::tensors() const { return {component(0), component(1), component(2)}; }

Eigen::VectorXd SeparatedField::local_nodal(const TensorGrid& grid) const {
  Eigen::VectorXd u(3 * grid.node_count());
  for (int i = 0; i < 3; ++i) {
    const Eigen::MatrixXd c = component(i);
    for (int k = 0; k < grid.thickness_nodes(); ++k)
      for (int a = 0; a < grid.plane_nodes(); ++a) u[3 * grid.node(a, k) + i] = c(a, k);
  }
  return u;
}

Eigen::VectorXd SeparatedField::cartesian_nodal(const TensorGrid& grid) const {
  Eigen::VectorXd u = local_nodal(grid);
  if (!grid.curved()) return u;
  for (int k = 0; k < grid.thickness_nodes(); ++k)
    for (int a = 0; a < grid.plane_nodes(); ++a) {
      const Eigen::Vector2d p = grid.plane_point(a);
      const Eigen::Matrix3d frame = grid.shape.local_frame(grid.shape.from_parametric({p[0], p[1], grid.t(k)}));
      const int n = grid.node(a, k);
      u.segment<3>(3 * n) = frame * Eigen::Vector3d(u.segment<3>(3 * n));
    }
  return u;
}

double SeparatedField::cartesian_at(const TensorGrid& grid, int plane_node, int thickness_node, int axis) const {
  Eigen::Vector3d local;
  for (std::size_t i = 0; i < 3; ++i) local[static_cast<Eigen::Index>(i)] = X[i].row(plane_node).dot(Z[i].row(thickness_node));
  if (!grid.curved()) return local[axis];
  const Eigen::Vector2d p = grid.plane_point(plane_node);
  const Eigen::Matrix3d frame = grid.shape.local_frame(grid.shape.from_parametric({p[0], p[1], grid.t(thickness_node)}));
  return frame.row(axis).dot(local);
}

void SeparatedField::compress(double relative_tolerance) {
  for (std::size_t i = 0; i < 3; ++i) {
    if (X[i].cols() == 0) continue;
    // X Z^T = Qx Rx Rz^T Qz^T; the SVD of the small core Rx Rz^T gives the orthogonal factors.
    Eigen::HouseholderQR<Eigen::MatrixXd> qx(X[i]), qz(Z[i]);
    const Eigen::Index q = X[i].cols();
    const Eigen::Index rx = std::min(q, X[i].rows()), rz = std::min(q, Z[i].rows());
    const Eigen::MatrixXd Rx = qx.matrixQR().topRows(rx).triangularView<Eigen::Upper>();
    const Eigen::MatrixXd Rz = qz.matrixQR().topRows(rz).triangularView<Eigen::Upper>();
    Eigen::JacobiSVD<Eigen::MatrixXd> svd(Rx * Rz.transpose(), Eigen::ComputeThinU | Eigen::ComputeThinV);
    const auto& s = svd.singularValues();
    Eigen::Index keep = 0;
    while (keep < s.size() && s[keep] > relative_tolerance * s[0]) ++keep;
    const Eigen::MatrixXd Qx = qx.householderQ() * Eigen::MatrixXd::Identity(X[i].rows(), rx);
    const Eigen::MatrixXd Qz = qz.householderQ() * Eigen::MatrixXd::Identity(Z[i].rows(), rz);
    X[i] = Qx * svd.matrixU().leftCols(keep) * s.head(keep).asDiagonal();
    Z[i] = Qz * svd.matrixV().leftCols(keep);
  }
}

void write_modes_hdf5(const std::filesystem::path& path, const TensorGrid& grid, const SeparatedField& field) {
  Hdf5Writer h5(path);
  const char* names[3] = {"u", "v", "w"};
  // Row-major datasets: one row per node, one column per term.
  auto rows = [](const Eigen::MatrixXd& m) {
    std::vector<double> v(static_cast<std::size_t>(m.size()));
    Eigen::Map<Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(v.data(), m.rows(), m.cols()) = m;
    return v;
  };
  for (std::size_t i = 0; i < 3; ++i) {
    h5.write(std::string("X_") + names[i], rows(field.X[i]), static_cast<std::size_t>(field.X[i].rows()), static_cast<std::size_t>(field.X[i].cols()));
    h5.write(std::string("Z_") + names[i], rows(field.Z[i]), static_cast<std::size_t>(field.Z[i].rows()), static_cast<std::size_t>(field.Z[i].cols()));
  }
  std::vector<double> u(static_cast<std::size_t>(grid.lattice_u())), v(static_cast<std::size_t>(grid.lattice_v())), t(static_cast<std::size_t>(grid.thickness_nodes()));
  for (int i = 0; i < grid.lattice_u(); ++i) u[static_cast<std::size_t>(i)] = grid.u(i);
  for (int j = 0; j < grid.lattice_v(); ++j) v[static_cast<std::size_t>(j)] = grid.v(j);
  for (int k = 0; k < grid.thickness_nodes(); ++k) t[static_cast<std::size_t>(k)] = grid.t(k);
  h5.write("plane_u", u, u.size(), 1);
  h5.write("plane_v", v, v.size(), 1);
  h5.write("thickness_t", t, t.size(), 1);
  h5.attribute("layout", std::string("component c (u, v, w along e1, e2, e3) = X_c Z_c^T; X rows: in-plane node j * len(plane_u) + i; "
                                     "Z rows: thickness node k"));
  h5.attribute("geometry", std::string(grid.curved() ? "panel" : "plate"));
  h5.commit();
}

}  // namespace drom::pgd
