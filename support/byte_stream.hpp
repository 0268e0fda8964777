#pragma once
// Plain binary packing of numbers, strings and dense matrices into one std::string: what one process
// hands another (MPI ranks) or leaves on disk for itself (checkpoints). Native byte order: the bytes
// are read back by the same build on the same kind of machine. Doubles travel bit for bit.
#include "support/input_error.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <cstring>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

namespace drom {

class ByteWriter {
 public:
  template <class T>
    requires std::is_arithmetic_v<T>
  void put(T value) {
    bytes_.append(reinterpret_cast<const char*>(&value), sizeof value);
  }
  void put(std::string_view text) {
    put<std::uint64_t>(text.size());
    bytes_.append(text);
  }
  template <class T>
    requires std::is_arithmetic_v<T>
  void put(const std::vector<T>& values) {
    put<std::uint64_t>(values.size());
    bytes_.append(reinterpret_cast<const char*>(values.data()), values.size() * sizeof(T));
  }
  void put(const Eigen::MatrixXd& m) {
    put<std::int64_t>(m.rows());
    put<std::int64_t>(m.cols());
    bytes_.append(reinterpret_cast<const char*>(m.data()), static_cast<std::size_t>(m.size()) * sizeof(double));
  }
  const std::string& bytes() const { return bytes_; }
  std::string take() { return std::move(bytes_); }

 private:
  std::string bytes_;
};

// Reads what a ByteWriter wrote, in the same order. A short or malformed buffer throws InputError
// naming `what` (the file or message it came from).
class ByteReader {
 public:
  ByteReader(std::string_view bytes, std::string what) : bytes_(bytes), what_(std::move(what)) {}

  template <class T>
    requires std::is_arithmetic_v<T>
  T get() {
    T value;
    std::memcpy(&value, take(sizeof value), sizeof value);
    return value;
  }
  std::string text() {
    const auto n = count(1);
    return std::string(take(n), n);
  }
  template <class T>
    requires std::is_arithmetic_v<T>
  std::vector<T> vector() {
    const auto n = count(sizeof(T));
    std::vector<T> values(n);
    if (n > 0) std::memcpy(values.data(), take(n * sizeof(T)), n * sizeof(T));
    return values;
  }
  Eigen::MatrixXd matrix() {
    const auto rows = get<std::int64_t>(), cols = get<std::int64_t>();
    if (rows < 0 || cols < 0 || (cols > 0 && static_cast<std::uint64_t>(rows) > remaining() / sizeof(double) / static_cast<std::uint64_t>(cols)))
      throw InputError(what_ + ": truncated or malformed (a matrix of " + std::to_string(rows) + " x " + std::to_string(cols) + ")");
    Eigen::MatrixXd m(rows, cols);
    if (m.size() > 0) std::memcpy(m.data(), take(static_cast<std::size_t>(m.size()) * sizeof(double)), static_cast<std::size_t>(m.size()) * sizeof(double));
    return m;
  }
  std::size_t remaining() const { return bytes_.size() - at_; }
  bool done() const { return at_ == bytes_.size(); }

 private:
  // A length prefix, checked against what is left (elements of `size` bytes).
  std::size_t count(std::size_t size) {
    const auto n = get<std::uint64_t>();
    if (n > remaining() / size) throw InputError(what_ + ": truncated or malformed (a length of " + std::to_string(n) + ")");
    return static_cast<std::size_t>(n);
  }
  const char* take(std::size_t n) {
    if (n > remaining()) throw InputError(what_ + ": truncated (" + std::to_string(remaining()) + " bytes left, " + std::to_string(n) + " needed)");
    const char* p = bytes_.data() + at_;
    at_ += n;
    return p;
  }
  std::string_view bytes_;
  std::string what_;
  std::size_t at_ = 0;
};

}  // namespace drom
