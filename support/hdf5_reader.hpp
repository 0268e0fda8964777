#pragma once
// Reads datasets and attributes written by Hdf5Writer (or by h5py). Errors name the file and the
// dataset.
#include <filesystem>
#include <string>
#include <vector>

namespace drom {

struct Hdf5Matrix {
  std::vector<double> data;  // row-major
  std::size_t rows = 0, cols = 0;
  double operator()(std::size_t r, std::size_t c) const { return data[r * cols + c]; }
};

class Hdf5Reader {
 public:
  explicit Hdf5Reader(const std::filesystem::path& path);  // throws InputError
  ~Hdf5Reader();
  Hdf5Reader(const Hdf5Reader&) = delete;
  Hdf5Reader& operator=(const Hdf5Reader&) = delete;

  bool has(const std::string& name) const;
  bool has_attribute(const std::string& name) const;
  const std::filesystem::path& path() const { return path_; }
  Hdf5Matrix matrix(const std::string& name) const;  // 1-D datasets come back as rows x 1
  std::string text_attribute(const std::string& name) const;
  double number_attribute(const std::string& name) const;

 private:
  std::filesystem::path path_;
  long long handle_;
};

}  // namespace drom
