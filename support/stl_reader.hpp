#pragma once
// STL files (ASCII or binary) as a list of triangles: the stock of a case (levelset/'s closed
// surfaces) and the check surfaces of an orientation case (paths/) are read by this one reader.
// Binary when the size is exactly 84 + 50 n bytes for the n the header announces, ASCII otherwise
// (keywords checked, each vertex three finite numbers). Every vertex lies within 10⁶ mm of the origin.
// Throws InputError naming the file, and the line or the facet.
#include <Eigen/Core>

#include <array>
#include <filesystem>
#include <vector>

namespace drom {

using StlFacet = std::array<Eigen::Vector3d, 3>;

std::vector<StlFacet> read_stl_facets(const std::filesystem::path& path);

}  // namespace drom
