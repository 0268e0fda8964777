#pragma once
// A surface seen from above: quadratic (or linear) faces of a volume mesh, located and interpolated
// by their horizontal projection. The target machined surface and the measured points live on it:
// a laser reading at (x, y) is interpolated from the face under it with the face's own shape
// functions (Quad8 serendipity, Quad9 Lagrange, Tri6; Quad4 and Tri3 too), so nodal fields are
// evaluated exactly as the FE mesh represents them.
#include <Eigen/Core>

#include <array>
#include <optional>
#include <vector>

namespace drom::reduce {

struct SurfacePoint {
  int face = -1;
  std::array<int, 9> nodes{};        // surface-node indices of the face (the first `count`)
  std::array<double, 9> weights{};   // shape functions at the point
  std::array<double, 9> dx{}, dy{};  // their horizontal derivatives d/dx, d/dy
  int count = 0;
};

class SurfaceMesh {
 public:
  SurfaceMesh() = default;
  // nodes: 3 x n nominal positions; faces: nodes_per_face entries each (corners counter-clockwise
  // seen from above, then edge midsides (edge k between corners k and k+1), then the centre).
  SurfaceMesh(Eigen::Matrix3Xd nodes, std::vector<int> faces, int nodes_per_face);

  int node_count() const { return static_cast<int>(nodes_.cols()); }
  int face_count() const { return static_cast<int>(faces_.size()) / per_face_; }
  int nodes_per_face() const { return per_face_; }
  const Eigen::Matrix3Xd& nodes() const { return nodes_; }
  const std::vector<int>& faces() const { return faces_; }

  // The face under (x, y) and the shape functions there; empty outside the surface's projection.
  // `hint`: a face to try first (the previous point's, for points along a profile); `slopes`: fill
  // dx and dy too (not needed to interpolate values).
  std::optional<SurfacePoint> locate(double x, double y, int hint = -1, bool slopes = true) const;
  // Interpolation of a nodal field (node_count rows) at a located point.
  template <class Field>
  auto interpolate(const SurfacePoint& p, const Field& f) const {
    auto v = (p.weights[0] * f.row(p.nodes[0])).eval();
    for (int k = 1; k < p.count; ++k) v += p.weights[static_cast<std::size_t>(k)] * f.row(p.nodes[static_cast<std::size_t>(k)]);
    return v;
  }
  double nominal_altitude(const SurfacePoint& p) const;

 private:
  bool inside_face(int face, double x, double y, SurfacePoint& out, bool slopes) const;
  struct FaceBox {
    double xmin, xmax, ymin, ymax;
    // Faces whose horizontal map is affine (straight sides, midsides at mid-edge: every face of a
    // structured plate mesh) are inverted in one step: (r, s) = inverse (x - origin).
    bool affine = false;
    Eigen::Vector2d origin;
    Eigen::Matrix2d inverse;
  };
  Eigen::Matrix3Xd nodes_;
  std::vector<FaceBox> boxes_;
  std::vector<int> faces_;
  int per_face_ = 0;
  // Uniform bucket grid over the projection: faces whose bounding box meets each cell.
  double x0_ = 0, y0_ = 0, cell_ = 1;
  int nx_ = 0, ny_ = 0;
  std::vector<std::vector<int>> buckets_;
};

// Face shape functions at reference point (xi, eta) and their reference derivatives.
void face_shape_functions(int nodes_per_face, double xi, double eta, double* N, double* dN_dxi, double* dN_deta);

}  // namespace drom::reduce
