#pragma once
// A dataset of a database or model file (row-major in HDF5) as an Eigen matrix.
#include "support/hdf5_reader.hpp"

#include <Eigen/Core>

#include <string>

namespace drom {

inline Eigen::MatrixXd read_matrix(const Hdf5Reader& h5, const std::string& name) {
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const Hdf5Matrix m = h5.matrix(name);
  return Eigen::Map<const RowMajor>(m.data.data(), static_cast<Eigen::Index>(m.rows), static_cast<Eigen::Index>(m.cols));
}

}  // namespace drom
