#include "support/hdf5_writer.hpp"

#include "support/file_integrity.hpp"

#include <hdf5.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace drom {

namespace {

// Before main, before any HDF5 call: no library shutdown at exit, and no error stack on stderr (drom
// says what failed). A file whose close failed (a full disk) stays in libhdf5's tables, and its
// shutdown then closes it again and crashes (libhdf5 1.10.8: SIGSEGV in H5F__close_cb). drom closes
// every file it opens, so the shutdown has nothing else to do.
[[maybe_unused]] const bool hdf5_quiet_and_no_atexit = [] {
  H5dont_atexit();
  H5Eset_auto2(H5E_DEFAULT, nullptr, nullptr);
  return true;
}();
// errno says why a write failed (a full disk: ENOSPC); HDF5's own stack is switched off (hdf5_reader.cpp).
void check(herr_t status, const std::string& what) {
  if (status < 0) throw std::runtime_error("HDF5: cannot " + what + (errno != 0 ? std::string(": ") + std::strerror(errno) : std::string()));
}

void write_dataset(hid_t file, const std::string& name, const void* data, hid_t type, std::size_t rows, std::size_t cols, int deflate_level) {
  const int rank = cols == 1 ? 1 : 2;
  const hsize_t dims[2] = {rows, cols};
  const hid_t space = H5Screate_simple(rank, dims, nullptr);
  const hid_t props = H5Pcreate(H5P_DATASET_CREATE);
  H5Pset_obj_track_times(props, 0);  // no timestamps: identical content gives identical files
  if (deflate_level > 0 && rows * cols >= 4096 && rows > 0 && cols > 0) {
    // Chunks of whole rows, about 256 kB each: a chunk per row would cost an index entry and a
    // deflate stream per row (measured: 4 MB of a 13 MB model was chunk overhead).
    const hsize_t element = H5Tget_size(type);
    const hsize_t rows_per_chunk = std::clamp<hsize_t>(262144 / (cols * element), 1, rows);
    const hsize_t chunk[2] = {rows_per_chunk, cols};
    const hsize_t chunk1[1] = {std::min<hsize_t>(rows, 65536)};
    check(H5Pset_chunk(props, rank, rank == 2 ? chunk : chunk1), "chunk " + name);
    check(H5Pset_deflate(props, static_cast<unsigned>(deflate_level)), "deflate " + name);
  }
  errno = 0;
  const hid_t set = H5Dcreate2(file, name.c_str(), type, space, H5P_DEFAULT, props, H5P_DEFAULT);
  herr_t written = set < 0 ? -1 : H5Dwrite(set, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, data);
  int error = errno;
  if (set >= 0 && H5Dclose(set) < 0 && written >= 0) written = -1, error = errno;  // the chunk cache is flushed here
  H5Pclose(props);
  H5Sclose(space);
  errno = error;
  check(written, "write dataset " + name);
}
}  // namespace

Hdf5Writer::Hdf5Writer(const std::filesystem::path& path, int deflate_level) : file_(path), deflate_level_(deflate_level) {
  if (deflate_level < 0 || deflate_level > 9) throw std::invalid_argument("Hdf5Writer: a deflate level from 0 (none) to 9 expected, not " + std::to_string(deflate_level));
  // The first kSealBytes are HDF5's user block: commit() writes the seal there (file_integrity.hpp).
  const hid_t create = H5Pcreate(H5P_FILE_CREATE);
  H5Pset_userblock(create, kSealBytes);
  errno = 0;
  handle_ = H5Fcreate(file_.temporary_path().c_str(), H5F_ACC_TRUNC, create, H5P_DEFAULT);
  H5Pclose(create);
  if (handle_ < 0) throw std::runtime_error("HDF5: cannot create " + file_.temporary_path().string() + (errno != 0 ? std::string(": ") + std::strerror(errno) : ""));
}

Hdf5Writer::~Hdf5Writer() {
  if (handle_ >= 0) H5Fclose(handle_);
}

void Hdf5Writer::write(const std::string& name, const std::vector<double>& data, std::size_t rows, std::size_t cols) {
  if (data.size() != rows * cols) throw std::invalid_argument("HDF5 dataset " + name + ": size mismatch");
  write_dataset(handle_, name, data.data(), H5T_NATIVE_DOUBLE, rows, cols, deflate_level_);
}

void Hdf5Writer::write(const std::string& name, const std::vector<float>& data, std::size_t rows, std::size_t cols) {
  if (data.size() != rows * cols) throw std::invalid_argument("HDF5 dataset " + name + ": size mismatch");
  write_dataset(handle_, name, data.data(), H5T_NATIVE_FLOAT, rows, cols, deflate_level_);
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
  errno = 0;
  const herr_t closed = H5Fclose(handle_);
  handle_ = -1;
  check(closed, "finish " + file_.temporary_path().string());
  seal_file(file_.temporary_path());
  file_.commit();
}

}  // namespace drom
