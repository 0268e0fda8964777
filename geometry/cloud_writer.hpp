#pragma once
// Point clouds written as PLY (binary little-endian or ascii), with their normals when they have them
// and any per-point scalars (a packet's number, a normal's error), for MeshLab, CloudCompare or
// ParaView. Atomic, like every drom output.
#include "geometry/point_cloud.hpp"

#include <filesystem>
#include <string>
#include <utility>
#include <vector>

namespace drom::geometry {

struct PlyScalar {
  std::string name;
  std::vector<double> values;  // one per point
  bool integer = false;        // written as int32, else float64
};

// The PLY's bytes; throws std::invalid_argument when a scalar's or the normals' count is not the points'.
std::string ply_bytes(const PointCloud& cloud, const std::vector<PlyScalar>& scalars = {}, bool binary = true);
void write_ply(const std::filesystem::path& path, const PointCloud& cloud, const std::vector<PlyScalar>& scalars = {}, bool binary = true);

}  // namespace drom::geometry
