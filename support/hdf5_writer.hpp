#pragma once
// Writes matrices and metadata to one HDF5 file, atomically (a temporary file renamed on commit()).
// Row-major datasets, readable with h5py as numpy arrays.
#include "support/atomic_file.hpp"

#include <cstdint>
#include <filesystem>
#include <string>
#include <vector>

namespace drom {

class Hdf5Writer {
 public:
  explicit Hdf5Writer(const std::filesystem::path& path);
  ~Hdf5Writer();
  Hdf5Writer(const Hdf5Writer&) = delete;
  Hdf5Writer& operator=(const Hdf5Writer&) = delete;

  // rows x cols, row-major; cols = 1 writes a 1-D dataset. Large datasets are chunked by row and
  // deflate-compressed.
  void write(const std::string& name, const std::vector<double>& data, std::size_t rows, std::size_t cols);
  void write(const std::string& name, const std::vector<float>& data, std::size_t rows, std::size_t cols);
  void attribute(const std::string& name, const std::string& value);
  void attribute(const std::string& name, double value);
  void commit();

 private:
  AtomicFile file_;
  std::int64_t handle_;
};

}  // namespace drom
