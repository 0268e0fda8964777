#include "support/hdf5_reader.hpp"

#include "support/file_integrity.hpp"
#include "support/input_error.hpp"

#include <hdf5.h>

namespace drom {

Hdf5Reader::Hdf5Reader(const std::filesystem::path& path) : path_(path) {
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);  // errors are reported by us, with context
  // No byte reaches libhdf5 unless it is what drom wrote: libhdf5 is not hardened against damaged
  // files (docs/robustness.md).
  check_seal(path);
  handle_ = H5Fopen(path.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (handle_ < 0) throw InputError(path.string() + ": not a readable HDF5 file");
}

Hdf5Reader::~Hdf5Reader() { H5Fclose(handle_); }

bool Hdf5Reader::has(const std::string& name) const { return H5Lexists(handle_, name.c_str(), H5P_DEFAULT) > 0; }

bool Hdf5Reader::has_attribute(const std::string& name) const { return H5Aexists(handle_, name.c_str()) > 0; }

Hdf5Matrix Hdf5Reader::matrix(const std::string& name) const {
  if (!has(name)) throw InputError(path_.string() + ": dataset '" + name + "' is missing");
  const hid_t set = H5Dopen2(handle_, name.c_str(), H5P_DEFAULT);
  const hid_t space = H5Dget_space(set);
  const int rank = H5Sget_simple_extent_ndims(space);
  hsize_t dims[2] = {0, 1};
  if (rank < 1 || rank > 2) {
    H5Sclose(space);
    H5Dclose(set);
    throw InputError(path_.string() + ": dataset '" + name + "' has rank " + std::to_string(rank) + ", expected 1 or 2");
  }
  H5Sget_simple_extent_dims(space, dims, nullptr);
  Hdf5Matrix m;
  m.rows = dims[0];
  m.cols = rank == 2 ? dims[1] : 1;
  m.data.resize(m.rows * m.cols);
  const herr_t status = H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, m.data.data());
  H5Sclose(space);
  H5Dclose(set);
  if (status < 0) throw InputError(path_.string() + ": cannot read dataset '" + name + "' as numbers");
  return m;
}

std::string Hdf5Reader::text_attribute(const std::string& name) const {
  if (H5Aexists(handle_, name.c_str()) <= 0) throw InputError(path_.string() + ": attribute '" + name + "' is missing");
  const hid_t attr = H5Aopen(handle_, name.c_str(), H5P_DEFAULT);
  const hid_t type = H5Aget_type(attr);
  std::string value;
  herr_t status = -1;
  if (H5Tget_class(type) == H5T_STRING && H5Tis_variable_str(type) > 0) {
    char* text = nullptr;
    status = H5Aread(attr, type, &text);
    if (status >= 0 && text) value = text;
    if (text) H5free_memory(text);
  } else if (H5Tget_class(type) == H5T_STRING) {
    value.assign(H5Tget_size(type), '\0');
    status = H5Aread(attr, type, value.data());
    value.resize(value.find('\0') == std::string::npos ? value.size() : value.find('\0'));
  }
  H5Tclose(type);
  H5Aclose(attr);
  if (status < 0) throw InputError(path_.string() + ": attribute '" + name + "' is not text");
  return value;
}

double Hdf5Reader::number_attribute(const std::string& name) const {
  if (H5Aexists(handle_, name.c_str()) <= 0) throw InputError(path_.string() + ": attribute '" + name + "' is missing");
  const hid_t attr = H5Aopen(handle_, name.c_str(), H5P_DEFAULT);
  double value = 0;
  const herr_t status = H5Aread(attr, H5T_NATIVE_DOUBLE, &value);
  H5Aclose(attr);
  if (status < 0) throw InputError(path_.string() + ": attribute '" + name + "' is not a number");
  return value;
}

}  // namespace drom
