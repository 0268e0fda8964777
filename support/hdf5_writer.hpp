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
  // deflate_level: zlib's level for the large datasets, 1 (fastest) to 9, or 0 to store them as they
  // are; 4 balances size and time for drom's databases and models.
  explicit Hdf5Writer(const std::filesystem::path& path, int deflate_level = 4);
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
  int deflate_level_;
};

}  // namespace drom
