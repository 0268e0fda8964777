#pragma once
// Structure-aware fuzzing of the files drom hands itself (the snapshot database, the light model).
// Flipped bytes never get past the seal (support/file_integrity.hpp), so the *_bytes harnesses test
// that; these harnesses test what comes after it: a file that is sealed and valid HDF5 but whose
// content is wrong (a dataset gone, reshaped, a NaN, a time out of order, a rank of 1e300), as a
// program other than drom, or a drom with a bug, could write. The input is an edit script applied to
// a base file written by drom_fuzz_seeds; the edited content is written (sealed) and read back.
#include "fuzz/fuzz_input.hpp"
#include "support/hdf5_writer.hpp"

#include <fuzzer/FuzzedDataProvider.h>
#include <hdf5.h>

#include <cmath>
#include <limits>
#include <string>
#include <vector>

namespace drom::fuzz {

struct Hdf5Dataset {
  std::string name;
  std::vector<double> values;  // row-major
  std::size_t rows = 0, cols = 1;
  bool single = false;  // written as float
};

struct Hdf5Attribute {
  std::string name, text;
  double number = 0;
  bool is_text = false;
};

struct Hdf5Content {
  std::vector<Hdf5Dataset> datasets;
  std::vector<Hdf5Attribute> attributes;
};

// The root group's datasets and attributes (the layout drom writes: everything at the root).
inline Hdf5Content read_content(const std::filesystem::path& file) {
  // Every file HDF5 opens gets a metadata cache of some 600 kB, allocated and zeroed; past its free
  // lists' default limit of 64 kB a list, HDF5 hands that block back to the allocator at close, and
  // under ASan every input then mapped and faulted it in twice (a third of the harness's time).
  // Kept on the free list, it is reused.
  H5set_free_list_limits(64 << 20, 16 << 20, -1, -1, -1, -1);
  Hdf5Content c;
  const hid_t f = H5Fopen(file.c_str(), H5F_ACC_RDONLY, H5P_DEFAULT);
  if (f < 0) finding("cannot open the base file " + file.string() + " (run drom_fuzz_seeds first)");
  H5Literate(
      f, H5_INDEX_NAME, H5_ITER_INC, nullptr,
      [](hid_t group, const char* name, const H5L_info_t*, void* out) -> herr_t {
        auto& content = *static_cast<Hdf5Content*>(out);
        const hid_t set = H5Dopen2(group, name, H5P_DEFAULT);
        const hid_t space = H5Dget_space(set), type = H5Dget_type(set);
        hsize_t dims[2] = {0, 1};
        const int rank = H5Sget_simple_extent_ndims(space);
        H5Sget_simple_extent_dims(space, dims, nullptr);
        Hdf5Dataset d{name, {}, dims[0], rank == 2 ? dims[1] : 1, H5Tget_size(type) == 4};
        d.values.resize(d.rows * d.cols);
        H5Dread(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, d.values.data());
        content.datasets.push_back(std::move(d));
        H5Tclose(type), H5Sclose(space), H5Dclose(set);
        return 0;
      },
      &c);
  H5Aiterate2(
      f, H5_INDEX_NAME, H5_ITER_INC, nullptr,
      [](hid_t object, const char* name, const H5A_info_t*, void* out) -> herr_t {
        auto& content = *static_cast<Hdf5Content*>(out);
        const hid_t attr = H5Aopen(object, name, H5P_DEFAULT), type = H5Aget_type(attr);
        Hdf5Attribute a{name, {}, 0, H5Tget_class(type) == H5T_STRING};
        if (a.is_text) {
          char* text = nullptr;
          H5Aread(attr, type, &text);
          a.text = text ? text : "";
          H5free_memory(text);
        } else {
          H5Aread(attr, H5T_NATIVE_DOUBLE, &a.number);
        }
        content.attributes.push_back(std::move(a));
        H5Tclose(type), H5Aclose(attr);
        return 0;
      },
      &c);
  H5Fclose(f);
  return c;
}

// A value a reader should think twice about.
inline double hostile_value(FuzzedDataProvider& in) {
  static const double values[] = {std::numeric_limits<double>::quiet_NaN(), std::numeric_limits<double>::infinity(), -std::numeric_limits<double>::infinity(),
                                  0.0, -0.0, -1.0, 1.0, 0.5, -0.5, 1e300, -1e300, 1e-300, 2147483648.0, -2147483649.0, 9.3e18, 1e9, 3.0, 4.0, 8.0, 27.0};
  if (in.ConsumeBool()) return values[in.ConsumeIntegralInRange<std::size_t>(0, std::size(values) - 1)];
  return in.ConsumeFloatingPoint<double>();
}

// Applies the edit script in `in` to `c`: each edit picks a dataset or attribute by index and removes
// it, reshapes it, sets or swaps its values, or rescales it.
inline void apply_edits(FuzzedDataProvider& in, Hdf5Content& c) {
  while (in.remaining_bytes() > 0) {
    const int op = in.ConsumeIntegralInRange(0, 7);
    if (op <= 3 && !c.datasets.empty()) {
      auto& d = c.datasets[in.ConsumeIntegralInRange<std::size_t>(0, c.datasets.size() - 1)];
      const std::size_t n = d.values.size();
      if (op == 0) {
        c.datasets.erase(c.datasets.begin() + (&d - c.datasets.data()));
      } else if (op == 1) {  // reshape, filling cyclically from the old values
        const std::size_t rows = in.ConsumeIntegralInRange<std::size_t>(0, 2 * d.rows + 2), cols = in.ConsumeIntegralInRange<std::size_t>(1, 2 * d.cols + 2);
        std::vector<double> v(rows * cols);
        for (std::size_t i = 0; i < v.size(); ++i) v[i] = n > 0 ? d.values[i % n] : 0.0;
        d.values = std::move(v), d.rows = rows, d.cols = cols;
      } else if (op == 2 && n > 0) {
        d.values[in.ConsumeIntegralInRange<std::size_t>(0, n - 1)] = hostile_value(in);
      } else if (op == 3 && n > 0) {  // swap two values (times out of order, faces renumbered)
        std::swap(d.values[in.ConsumeIntegralInRange<std::size_t>(0, n - 1)], d.values[in.ConsumeIntegralInRange<std::size_t>(0, n - 1)]);
      }
    } else if (op >= 4 && op <= 6 && !c.attributes.empty()) {
      auto& a = c.attributes[in.ConsumeIntegralInRange<std::size_t>(0, c.attributes.size() - 1)];
      if (op == 4) {
        c.attributes.erase(c.attributes.begin() + (&a - c.attributes.data()));
      } else if (op == 5 && !a.is_text) {
        a.number = hostile_value(in);
      } else if (op == 5 || op == 6) {
        a.text = in.ConsumeRandomLengthString(64);
      }
    } else if (op == 7 && !c.datasets.empty()) {
      auto& d = c.datasets[in.ConsumeIntegralInRange<std::size_t>(0, c.datasets.size() - 1)];
      const double k = hostile_value(in);
      for (auto& v : d.values) v *= k;
    }
  }
}

inline void write_content(const Hdf5Content& c, const std::filesystem::path& file) {
  // Stored uncompressed: deflating the base's snapshots was a third of an input's time (at level 4 or
  // 1 alike), and what the deflate filter does on reading is libhdf5's work, not drom's reader's.
  Hdf5Writer h5(file, 0);
  for (const auto& d : c.datasets) {
    if (d.single) {
      // Past float's range: infinite, as IEEE arithmetic rounds it (a cast would be UB).
      auto to_float = [](double x) {
        constexpr float inf = std::numeric_limits<float>::infinity();
        if (std::isnan(x)) return std::numeric_limits<float>::quiet_NaN();
        if (std::abs(x) > std::numeric_limits<float>::max()) return x > 0 ? inf : -inf;
        return static_cast<float>(x);
      };
      std::vector<float> v(d.values.size());
      for (std::size_t i = 0; i < v.size(); ++i) v[i] = to_float(d.values[i]);
      h5.write(d.name, v, d.rows, d.cols);
    }
    else
      h5.write(d.name, d.values, d.rows, d.cols);
  }
  for (const auto& a : c.attributes) {
    if (a.is_text)
      h5.attribute(a.name, a.text);
    else
      h5.attribute(a.name, a.number);
  }
  h5.commit();
}

// The base file's content edited by the input, written (sealed) to scratch_dir()/name.
inline std::filesystem::path edited_file(const Hdf5Content& base, const std::uint8_t* data, std::size_t size, const std::string& name) {
  Hdf5Content c = base;
  FuzzedDataProvider in(data, size);
  apply_edits(in, c);
  const auto file = scratch_dir() / name;
  write_content(c, file);
  return file;
}

}  // namespace drom::fuzz
