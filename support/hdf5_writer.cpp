#include "support/hdf5_writer.hpp"

#include <hdf5.h>

#include <algorithm>
#include <stdexcept>

namespace drom {

namespace {
void check(herr_t status, const std::string& what) {
  if (status < 0) throw std::runtime_error("HDF5: " + what);
}

void write_dataset(hid_t file, const std::string& name, const void* data, hid_t type, std::size_t rows, std::size_t cols) {
  const int rank = cols == 1 ? 1 : 2;
  const hsize_t dims[2] = {rows, cols};
  const hid_t space = H5Screate_simple(rank, dims, nullptr);
  const hid_t props = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_obj_track_times(props, 0);  // no timestamps: identical content gives identical files
  if (rows * cols >= 4096 && rows > 0 && cols > 0) {
    // Chunks of whole rows, about 256 kB each: a chunk per row would cost an index entry and a
    // deflate stream per row (measured: 4 MB of a 13 MB model was chunk overhead).
    const hsize_t element = H5Tget_size(type);
    const hsize_t rows_per_chunk = std::clamp<hsize_t>(262144 / (cols * element), 1, rows);
    const hsize_t chunk[2] = {rows_per_chunk, cols};
    const hsize_t chunk1[1] = {std::min<hsize_t>(rows, 65536)};
    check(H5Pset_chunk(props, rank, rank == 2 ? chunk : chunk1), "chunk " + name);
    check(H5Pset_deflate(props, 4), "deflate " + name);
  }
  const hid_t set = H5Dcreate2(file, name.c_str(), type, space, H5P_DEFAULT, props, H5P_DEFAULT);
  if (set < 0) throw std::runtime_error("HDF5: cannot create dataset " + name);
  check(H5Dwrite(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data), "write " + name);
  H5Dclose(set);
  H5Pclose(props);
  H5Sclose(space);
}
}  // namespace

Hdf5Writer::Hdf5Writer(const std::filesystem::path& path) : file_(path) {
  handle_ = H5Fcreate(file_.temporary_path().c_str(), H5F_ACC_TRUNC, H5P_DEFAULT, H5P_DEFAULT);
  if (handle_ < 0) throw std::runtime_error("HDF5: cannot create " + file_.temporary_path().string());
}

Hdf5Writer::~Hdf5Writer() {
  if (handle_ >= 0) H5Fclose(handle_);
}

void Hdf5Writer::write(const std::string& name, const std::vector<double>& data, std::size_t rows, std::size_t cols) {
  if (data.size() != rows * cols) throw std::invalid_argument("HDF5 dataset " + name + ": size mismatch");
  write_dataset(handle_, name, data.data(), H5T_NATIVE_DOUBLE, rows, cols);
}

void Hdf5Writer::write(const std::string& name, const std::vector<float>& data, std::size_t rows, std::size_t cols) {
  if (data.size() != rows * cols) throw std::invalid_argument("HDF5 dataset " + name + ": size mismatch");
  write_dataset(handle_, name, data.data(), H5T_NATIVE_FLOAT, rows, cols);
}

void Hdf5Writer::attribute(const std::string& name, const std::string& value) {
  // Variable-length UTF-8: h5py reads it back as a Python str, not bytes.
  const hid_t type = H5Tcopy(H5T_C_S1);
  H5Tset_size(type, H5T_VARIABLE);
  H5Tset_cset(type, H5T_CSET_UTF8);
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t attr = H5Acreate2(handle_, name.c_str(), type, space, H5P_DEFAULT, H5P_DEFAULT);
  const char* text = value.c_str();
  check(H5Awrite(attr, type, &text), "attribute " + name);
  H5Aclose(attr);
  H5Sclose(space);
  H5Tclose(type);
}

void Hdf5Writer::attribute(const std::string& name, double value) {
  const hid_t space = H5Screate(H5S_SCALAR);
  const hid_t attr = H5Acreate2(handle_, name.c_str(), H5T_NATIVE_DOUBLE, space, H5P_DEFAULT, H5P_DEFAULT);
  check(H5Awrite(attr, H5T_NATIVE_DOUBLE, &value), "attribute " + name);
  H5Aclose(attr);
  H5Sclose(space);
}

void Hdf5Writer::commit() {
  check(H5Fclose(handle_), "close");
  handle_ = -1;
  file_.commit();
}

}  // namespace drom
