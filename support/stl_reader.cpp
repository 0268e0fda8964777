#include "support/stl_reader.hpp"

#include "support/input_error.hpp"

#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

namespace drom {

namespace {
// Far past any machine: what lies beyond is a damaged file, and its products would overflow.
bool within_reach(const Eigen::Vector3d& v) { return v.allFinite() && v.cwiseAbs().maxCoeff() <= 1e6; }
}  // namespace

std::vector<StlFacet> read_stl_facets(const std::filesystem::path& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(path.string() + ": cannot open STL file");
  std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  std::vector<StlFacet> triangles;

  auto binary_size_matches = [&] {
    if (bytes.size() < 84) return false;
    std::uint32_t n = 0;
    std::memcpy(&n, bytes.data() + 80, 4);
    return bytes.size() == 84 + 50ull * n;
  };
  if (binary_size_matches()) {
    std::uint32_t n = 0;
    std::memcpy(&n, bytes.data() + 80, 4);
    for (std::uint32_t t = 0; t < n; ++t) {
      const char* rec = bytes.data() + 84 + 50ull * t + 12;  // skip the normal
      StlFacet tri;
      for (int v = 0; v < 3; ++v) {
        float xyz[3];
        std::memcpy(xyz, rec + 12 * v, 12);
        tri[static_cast<std::size_t>(v)] = Eigen::Vector3d(xyz[0], xyz[1], xyz[2]);
        if (!within_reach(tri[static_cast<std::size_t>(v)]))
          throw InputError(path.string() + ": facet " + std::to_string(t + 1) + " has a vertex that is not finite or beyond any part (|x|, |y|, |z| <= 1e6 mm)");
      }
      triangles.push_back(tri);
    }
    return triangles;
  }

  std::istringstream text(bytes);
  std::string line, word;
  int line_no = 0, vertex_in_facet = 0;
  bool seen_solid = false;
  StlFacet tri;
  while (std::getline(text, line)) {
    ++line_no;
    std::istringstream ls(line);
    if (!(ls >> word)) continue;
    const std::string where = path.string() + ":" + std::to_string(line_no) + ": ";
    if (word == "solid") {
      seen_solid = true;
    } else if (word == "facet") {
      vertex_in_facet = 0;
    } else if (word == "vertex") {
      double x, y, z;
      if (!(ls >> x >> y >> z) || !within_reach(Eigen::Vector3d(x, y, z)))
        throw InputError(where + "expected 'vertex x y z' with three finite numbers within 1e6 mm");
      if (vertex_in_facet >= 3) throw InputError(where + "facet has more than three vertices");
      tri[static_cast<std::size_t>(vertex_in_facet++)] = Eigen::Vector3d(x, y, z);
    } else if (word == "endfacet") {
      if (vertex_in_facet != 3) throw InputError(where + "facet has " + std::to_string(vertex_in_facet) + " vertices, expected 3");
      triangles.push_back(tri);
    } else if (word != "outer" && word != "endloop" && word != "endsolid") {
      throw InputError(where + "unexpected '" + word + "' (expected an ASCII STL keyword)");
    }
  }
  if (!seen_solid) throw InputError(path.string() + ": neither a binary STL (size mismatch) nor an ASCII one ('solid' missing)");
  return triangles;
}

}  // namespace drom
