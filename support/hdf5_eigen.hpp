#pragma once
// A dataset of a database or model file (row-major in HDF5) as an Eigen matrix.
#include "support/hdf5_reader.hpp"
#include "support/input_error.hpp"

#include <Eigen/Core>

#include <cmath>
#include <sstream>
#include <string>

namespace drom {

inline Eigen::MatrixXd read_matrix(const Hdf5Reader& h5, const std::string& name) {
  using RowMajor = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  const Hdf5Matrix m = h5.matrix(name);
  return Eigen::Map<const RowMajor>(m.data.data(), static_cast<Eigen::Index>(m.rows), static_cast<Eigen::Index>(m.cols));
}

// The same for a dataset that holds numbers only (databases, models): a NaN or an infinity is a damaged
// or forged file, refused naming the dataset, row and column.
inline Eigen::MatrixXd read_finite_matrix(const Hdf5Reader& h5, const std::string& name) {
  Eigen::MatrixXd m = read_matrix(h5, name);
  for (Eigen::Index r = 0; r < m.rows(); ++r)
    for (Eigen::Index c = 0; c < m.cols(); ++c)
      if (!std::isfinite(m(r, c)))
        throw InputError(h5.path().string() + ": dataset '" + name + "' holds " + std::to_string(m(r, c)) + " at row " + std::to_string(r) + ", column " +
                         std::to_string(c) + ": finite numbers expected");
  return m;
}

// A dataset's values within `most` in magnitude. Finite values near 1e300 pass read_finite_matrix and
// overflow the products made of them later; `what` names what the values are and the bound
// ("any displacement (mm) or time (s) of a job (|value| <= 1e7)").
inline void require_magnitude_within(const Hdf5Reader& h5, const std::string& name, const Eigen::MatrixXd& m, double most, const std::string& what) {
  if (m.size() == 0 || m.cwiseAbs().maxCoeff() <= most) return;
  std::ostringstream largest;
  largest << m.cwiseAbs().maxCoeff();
  throw InputError(h5.path().string() + ": dataset '" + name + "' holds a value of magnitude " + largest.str() + ", beyond " + what);
}

}  // namespace drom
