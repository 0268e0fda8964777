// Harness: a point cloud (geometry/cloud_reader.hpp) as drom copy reads it: XYZ/CSV text, PLY
// (ascii, binary little- and big-endian) when the bytes start with "ply", or PCD (ascii, binary,
// binary_compressed) when they start with its header. Seeds: a sphere cap sampled with and without
// normals, in each format, and a two-point compressed PCD.
#include "fuzz/fuzz_input.hpp"
#include "geometry/cloud_reader.hpp"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string origin = "fuzz_cloud";
  drom::fuzz::expect_clean(
      [&] {
        const auto cloud = drom::geometry::parse_cloud(drom::fuzz::as_text(data, size), origin);
        drom::fuzz::require(cloud.size() > 0, "an empty cloud accepted");
        drom::fuzz::require(cloud.normals.empty() || cloud.normals.size() == cloud.points.size(), "normals not one per point");
        for (const auto& p : cloud.points) drom::fuzz::require(p.allFinite(), "a non-finite point");
        for (const auto& n : cloud.normals) drom::fuzz::require(n.allFinite() && std::abs(n.norm() - 1) < 1e-6, "a normal that is not a unit vector");
      },
      origin);
  return 0;
}
