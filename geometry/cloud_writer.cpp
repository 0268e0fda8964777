#include "geometry/cloud_writer.hpp"

#include "support/atomic_file.hpp"

#include <bit>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace drom::geometry {

namespace {

template <class T>
void append_little_endian(std::string& out, T value) {
  char b[sizeof(T)];
  std::memcpy(b, &value, sizeof(T));
  if constexpr (std::endian::native == std::endian::big)
    for (std::size_t i = 0; i < sizeof(T) / 2; ++i) std::swap(b[i], b[sizeof(T) - 1 - i]);
  out.append(b, sizeof(T));
}

void append_number(std::string& out, double v) {
  char buffer[32];
  const int n = std::snprintf(buffer, sizeof buffer, "%.17g", v);
  out.append(buffer, static_cast<std::size_t>(n));
}

}  // namespace

std::string ply_bytes(const PointCloud& cloud, const std::vector<PlyScalar>& scalars, bool binary) {
  const std::size_t n = cloud.size();
  if (cloud.has_normals() && cloud.normals.size() != n) throw std::invalid_argument("ply_bytes: " + std::to_string(cloud.normals.size()) + " normals for " + std::to_string(n) + " points");
  for (const auto& s : scalars)
    if (s.values.size() != n) throw std::invalid_argument("ply_bytes: scalar '" + s.name + "' has " + std::to_string(s.values.size()) + " values for " + std::to_string(n) + " points");
  std::string out = "ply\nformat ";
  out += binary ? "binary_little_endian 1.0\n" : "ascii 1.0\n";
  out += "comment written by drom (" + cloud.origin + ")\n";
  out += "element vertex " + std::to_string(n) + "\n";
  out += "property double x\nproperty double y\nproperty double z\n";
  if (cloud.has_normals()) out += "property double nx\nproperty double ny\nproperty double nz\n";
  for (const auto& s : scalars) out += std::string("property ") + (s.integer ? "int" : "double") + " " + s.name + "\n";
  out += "end_header\n";
  out.reserve(out.size() + n * (binary ? 8 * (3 + 3 * cloud.has_normals() + scalars.size()) : 40 * (3 + 3 * cloud.has_normals() + scalars.size())));
  for (std::size_t i = 0; i < n; ++i) {
    const auto put = [&](double v, bool integer) {
      if (binary) {
        if (integer) append_little_endian(out, static_cast<std::int32_t>(v));
        else append_little_endian(out, v);
      } else {
        if (!out.empty() && out.back() != '\n') out += ' ';
        append_number(out, integer ? static_cast<double>(static_cast<std::int32_t>(v)) : v);
      }
    };
    for (int k = 0; k < 3; ++k) put(cloud.points[i][k], false);
    if (cloud.has_normals())
      for (int k = 0; k < 3; ++k) put(cloud.normals[i][k], false);
    for (const auto& s : scalars) put(s.values[i], s.integer);
    if (!binary) out += '\n';
  }
  return out;
}

void write_ply(const std::filesystem::path& path, const PointCloud& cloud, const std::vector<PlyScalar>& scalars, bool binary) {
  write_file_atomically(path, ply_bytes(cloud, scalars, binary));
}

}  // namespace drom::geometry
