#include "fem/tet_mesh.hpp"

#include "support/input_error.hpp"

#include <tetgen.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>

namespace drom::fem {

Mesh make_tet_mesh(const Plc& plc, const TetMeshSpec& spec) {
  tetgenio in, out;
  in.firstnumber = 0;
  in.numberofpoints = static_cast<int>(plc.points.size());
  in.pointlist = new REAL[plc.points.size() * 3];
  for (std::size_t i = 0; i < plc.points.size(); ++i)
    for (int k = 0; k < 3; ++k) in.pointlist[3 * i + static_cast<std::size_t>(k)] = plc.points[i][k];
  in.numberoffacets = static_cast<int>(plc.facets.size());
  in.facetlist = new tetgenio::facet[plc.facets.size()];
  for (std::size_t f = 0; f < plc.facets.size(); ++f) {
    tetgenio::facet& facet = in.facetlist[f];
    tetgenio::init(&facet);
    facet.numberofpolygons = 1;
    facet.polygonlist = new tetgenio::polygon[1];
    tetgenio::init(&facet.polygonlist[0]);
    facet.polygonlist[0].numberofvertices = static_cast<int>(plc.facets[f].size());
    facet.polygonlist[0].vertexlist = new int[plc.facets[f].size()];
    std::copy(plc.facets[f].begin(), plc.facets[f].end(), facet.polygonlist[0].vertexlist);
  }

  std::ostringstream sw;
  sw << "pQq" << spec.radius_edge_ratio;
  if (spec.min_dihedral_deg > 0) sw << "/" << spec.min_dihedral_deg;
  if (spec.max_volume > 0) sw << "a" << spec.max_volume;
  std::string switches = sw.str();
  try {
    tetrahedralize(switches.data(), &in, &out);
  } catch (int code) {
    throw InputError("TetGen failed (code " + std::to_string(code) +
                     "): the surface may self-intersect or have overlapping facets");
  }
  if (out.numberoftetrahedra == 0) throw InputError("TetGen produced no tetrahedra");

  Mesh mesh;
  mesh.type = ElementType::Tet10;
  for (int i = 0; i < out.numberofpoints; ++i)
    mesh.nodes.emplace_back(out.pointlist[3 * i], out.pointlist[3 * i + 1], out.pointlist[3 * i + 2]);
  std::map<std::pair<int, int>, int> midside;
  auto mid = [&](int a, int b) {
    const std::pair<int, int> key{std::min(a, b), std::max(a, b)};
    auto [it, inserted] = midside.try_emplace(key, mesh.node_count());
    if (inserted) mesh.nodes.push_back(0.5 * (mesh.nodes[static_cast<std::size_t>(a)] + mesh.nodes[static_cast<std::size_t>(b)]));
    return it->second;
  };
  mesh.connectivity.reserve(static_cast<std::size_t>(out.numberoftetrahedra) * 10);
  for (int t = 0; t < out.numberoftetrahedra; ++t) {
    std::array<int, 4> c;
    for (int k = 0; k < 4; ++k) c[static_cast<std::size_t>(k)] = out.tetrahedronlist[t * out.numberofcorners + k];
    const auto& p = mesh.nodes;
    const double vol = (p[static_cast<std::size_t>(c[1])] - p[static_cast<std::size_t>(c[0])])
                           .cross(p[static_cast<std::size_t>(c[2])] - p[static_cast<std::size_t>(c[0])])
                           .dot(p[static_cast<std::size_t>(c[3])] - p[static_cast<std::size_t>(c[0])]);
    if (vol < 0) std::swap(c[1], c[2]);  // VTK order needs a positive orientation
    const int e01 = mid(c[0], c[1]), e12 = mid(c[1], c[2]), e02 = mid(c[0], c[2]);
    const int e03 = mid(c[0], c[3]), e13 = mid(c[1], c[3]), e23 = mid(c[2], c[3]);
    for (int v : {c[0], c[1], c[2], c[3], e01, e12, e02, e03, e13, e23}) mesh.connectivity.push_back(v);
  }
  return mesh;
}

}  // namespace drom::fem
