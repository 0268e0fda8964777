#include "reduce/surface_mesh.hpp"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace drom::reduce {

namespace {
bool is_triangle(int n) { return n == 3 || n == 6; }
}  // namespace

void face_shape_functions(int n, double r, double s, double* N, double* Nr, double* Ns) {
  switch (n) {
    case 3:
      N[0] = 1 - r - s, N[1] = r, N[2] = s;
      Nr[0] = -1, Nr[1] = 1, Nr[2] = 0;
      Ns[0] = -1, Ns[1] = 0, Ns[2] = 1;
      return;
    case 6: {
      const double l0 = 1 - r - s;
      N[0] = l0 * (2 * l0 - 1), N[1] = r * (2 * r - 1), N[2] = s * (2 * s - 1);
      N[3] = 4 * l0 * r, N[4] = 4 * r * s, N[5] = 4 * s * l0;
      Nr[0] = -(4 * l0 - 1), Nr[1] = 4 * r - 1, Nr[2] = 0, Nr[3] = 4 * (l0 - r), Nr[4] = 4 * s, Nr[5] = -4 * s;
      Ns[0] = -(4 * l0 - 1), Ns[1] = 0, Ns[2] = 4 * s - 1, Ns[3] = -4 * r, Ns[4] = 4 * r, Ns[5] = 4 * (l0 - s);
      return;
    }
    case 4: {
      const double rc[4] = {-1, 1, 1, -1}, sc[4] = {-1, -1, 1, 1};
      for (int k = 0; k < 4; ++k) {
        N[k] = 0.25 * (1 + rc[k] * r) * (1 + sc[k] * s);
        Nr[k] = 0.25 * rc[k] * (1 + sc[k] * s);
        Ns[k] = 0.25 * sc[k] * (1 + rc[k] * r);
      }
      return;
    }
    case 8: {
      const double rc[4] = {-1, 1, 1, -1}, sc[4] = {-1, -1, 1, 1};
      for (int k = 0; k < 4; ++k) {
        const double a = 1 + rc[k] * r, b = 1 + sc[k] * s, c = rc[k] * r + sc[k] * s - 1;
        N[k] = 0.25 * a * b * c;
        Nr[k] = 0.25 * rc[k] * b * (c + a);
        Ns[k] = 0.25 * sc[k] * a * (c + b);
      }
      // midsides: (0,-1), (1,0), (0,1), (-1,0)
      N[4] = 0.5 * (1 - r * r) * (1 - s), Nr[4] = -r * (1 - s), Ns[4] = -0.5 * (1 - r * r);
      N[5] = 0.5 * (1 + r) * (1 - s * s), Nr[5] = 0.5 * (1 - s * s), Ns[5] = -s * (1 + r);
      N[6] = 0.5 * (1 - r * r) * (1 + s), Nr[6] = -r * (1 + s), Ns[6] = 0.5 * (1 - r * r);
      N[7] = 0.5 * (1 - r) * (1 - s * s), Nr[7] = -0.5 * (1 - s * s), Ns[7] = -s * (1 - r);
      return;
    }
    case 9: {
      // Lagrange: products of 1D quadratics at -1, 0, 1; node (i, j) per VTK face order.
      auto l = [](double x, int i) { return i == 0 ? 0.5 * x * (x - 1) : i == 1 ? 1 - x * x : 0.5 * x * (x + 1); };
      auto dl = [](double x, int i) { return i == 0 ? x - 0.5 : i == 1 ? -2 * x : x + 0.5; };
      const int ri[9] = {0, 2, 2, 0, 1, 2, 1, 0, 1}, si[9] = {0, 0, 2, 2, 0, 1, 2, 1, 1};
      for (int k = 0; k < 9; ++k) {
        N[k] = l(r, ri[k]) * l(s, si[k]);
        Nr[k] = dl(r, ri[k]) * l(s, si[k]);
        Ns[k] = l(r, ri[k]) * dl(s, si[k]);
      }
      return;
    }
    default:
      throw std::invalid_argument("surface faces must have 3, 4, 6, 8 or 9 nodes, not " + std::to_string(n));
  }
}

SurfaceMesh::SurfaceMesh(Eigen::Matrix3Xd nodes, std::vector<int> faces, int nodes_per_face)
    : nodes_(std::move(nodes)), faces_(std::move(faces)), per_face_(nodes_per_face) {
  double N[9], Nr[9], Ns[9];
  face_shape_functions(per_face_, 0, 0, N, Nr, Ns);  // validates nodes_per_face
  if (faces_.size() % static_cast<std::size_t>(per_face_) != 0) throw std::invalid_argument("surface mesh: face list is not a whole number of faces");
  for (int v : faces_)
    if (v < 0 || v >= node_count()) throw std::invalid_argument("surface mesh: face node " + std::to_string(v) + " out of range");
  if (face_count() == 0) return;
  // Bucket grid: about one face per cell.
  const Eigen::Vector3d lo = nodes_.rowwise().minCoeff(), hi = nodes_.rowwise().maxCoeff();
  const double span = std::max({hi.x() - lo.x(), hi.y() - lo.y(), 1e-9});
  const int per_side = std::max(1, static_cast<int>(std::sqrt(static_cast<double>(face_count()))));
  cell_ = span / per_side * (1 + 1e-9);
  x0_ = lo.x(), y0_ = lo.y();
  nx_ = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / cell_)) + 1);
  ny_ = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / cell_)) + 1);
  buckets_.assign(static_cast<std::size_t>(nx_ * ny_), {});
  boxes_.resize(static_cast<std::size_t>(face_count()));
  for (int f = 0; f < face_count(); ++f) {
    double xmin = 1e300, xmax = -1e300, ymin = 1e300, ymax = -1e300;
    for (int k = 0; k < per_face_; ++k) {
      const auto p = nodes_.col(faces_[static_cast<std::size_t>(f * per_face_ + k)]);
      xmin = std::min(xmin, p.x()), xmax = std::max(xmax, p.x()), ymin = std::min(ymin, p.y()), ymax = std::max(ymax, p.y());
    }
    FaceBox& box = boxes_[static_cast<std::size_t>(f)];
    const double pad = 1e-9 * span;
    box.xmin = xmin - pad, box.xmax = xmax + pad, box.ymin = ymin - pad, box.ymax = ymax + pad;
    // Affine if every node sits where the affine map through the corners puts its reference position.
    const int* conn = faces_.data() + static_cast<std::size_t>(f) * per_face_;
    const bool tri = is_triangle(per_face_);
    const Eigen::Vector2d c0 = nodes_.col(conn[0]).head<2>(), c1 = nodes_.col(conn[1]).head<2>(), c2 = nodes_.col(conn[tri ? 2 : 3]).head<2>();
    Eigen::Matrix2d A;  // d(x, y)/d(r, s)
    if (tri) {
      A.col(0) = c1 - c0, A.col(1) = c2 - c0;
      box.origin = c0;
    } else {
      A.col(0) = 0.5 * (c1 - c0), A.col(1) = 0.5 * (c2 - c0);
      box.origin = c0 + A.col(0) + A.col(1);
    }
    box.affine = std::abs(A.determinant()) > 0;
    if (box.affine) box.inverse = A.inverse();
    for (int k = 0; k < per_face_ && box.affine; ++k) {
      const Eigen::Vector2d rs = box.inverse * (nodes_.col(conn[k]).head<2>() - box.origin);
      face_shape_functions(per_face_, rs.x(), rs.y(), N, Nr, Ns);
      box.affine = std::abs(N[k] - 1) < 1e-9;
    }
    const int i0 = std::clamp(static_cast<int>((xmin - x0_) / cell_), 0, nx_ - 1), i1 = std::clamp(static_cast<int>((xmax - x0_) / cell_), 0, nx_ - 1);
    const int j0 = std::clamp(static_cast<int>((ymin - y0_) / cell_), 0, ny_ - 1), j1 = std::clamp(static_cast<int>((ymax - y0_) / cell_), 0, ny_ - 1);
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) buckets_[static_cast<std::size_t>(j * nx_ + i)].push_back(f);
  }
}

bool SurfaceMesh::inside_face(int f, double x, double y, SurfacePoint& out, bool slopes) const {
  const int n = per_face_;
  const int* conn = faces_.data() + static_cast<std::size_t>(f) * n;
  const FaceBox& box = boxes_[static_cast<std::size_t>(f)];
  if (x < box.xmin || x > box.xmax || y < box.ymin || y > box.ymax) return false;
  double N[9], Nr[9], Ns[9];
  // Newton on the horizontal map (r, s) -> (x, y), from the face's centre (one step for affine faces).
  double r = is_triangle(n) ? 1.0 / 3 : 0, s = r;
  Eigen::Matrix2d J;
  if (box.affine) {
    const Eigen::Vector2d rs = box.inverse * (Eigen::Vector2d(x, y) - box.origin);
    r = rs.x(), s = rs.y();
  }
  for (int it = 0; it < 12 && !box.affine; ++it) {
    face_shape_functions(n, r, s, N, Nr, Ns);
    double fx = -x, fy = -y;
    J.setZero();
    for (int k = 0; k < n; ++k) {
      const auto p = nodes_.col(conn[k]);
      fx += N[k] * p.x(), fy += N[k] * p.y();
      J(0, 0) += Nr[k] * p.x(), J(0, 1) += Ns[k] * p.x(), J(1, 0) += Nr[k] * p.y(), J(1, 1) += Ns[k] * p.y();
    }
    const double det = J.determinant();
    if (!(std::abs(det) > 0)) return false;
    const Eigen::Vector2d step = J.inverse() * Eigen::Vector2d(fx, fy);
    r -= step.x(), s -= step.y();
    if (std::abs(r) > 3 || std::abs(s) > 3) return false;
    if (step.norm() < 1e-13) break;
  }
  const double tol = 1e-9;
  const bool inside = is_triangle(n) ? (r >= -tol && s >= -tol && r + s <= 1 + tol) : (std::abs(r) <= 1 + tol && std::abs(s) <= 1 + tol);
  if (!inside) return false;
  face_shape_functions(n, r, s, N, Nr, Ns);
  out.face = f;
  out.count = n;
  for (int k = 0; k < n; ++k) {
    out.nodes[static_cast<std::size_t>(k)] = conn[k];
    out.weights[static_cast<std::size_t>(k)] = N[k];
  }
  if (!slopes) return true;
  Eigen::Matrix2d Jinv;  // d(r, s)/d(x, y)
  if (box.affine) {
    Jinv = box.inverse;
  } else {
    J.setZero();
    for (int k = 0; k < n; ++k) {
      const auto p = nodes_.col(conn[k]);
      J(0, 0) += Nr[k] * p.x(), J(0, 1) += Ns[k] * p.x(), J(1, 0) += Nr[k] * p.y(), J(1, 1) += Ns[k] * p.y();
    }
    Jinv = J.inverse();
  }
  for (int k = 0; k < n; ++k) {
    const auto kk = static_cast<std::size_t>(k);
    out.dx[kk] = Nr[k] * Jinv(0, 0) + Ns[k] * Jinv(1, 0);
    out.dy[kk] = Nr[k] * Jinv(0, 1) + Ns[k] * Jinv(1, 1);
  }
  return true;
}

std::optional<SurfacePoint> SurfaceMesh::locate(double x, double y, int hint, bool slopes) const {
  if (buckets_.empty() || !std::isfinite(x) || !std::isfinite(y)) return std::nullopt;
  SurfacePoint p;
  if (hint >= 0 && hint < face_count() && inside_face(hint, x, y, p, slopes)) return p;
  // Compared as doubles first: a point far off the mesh has a cell index past an int (finding 22).
  const double fi = std::floor((x - x0_) / cell_), fj = std::floor((y - y0_) / cell_);
  if (!(fi >= 0 && fj >= 0 && fi < nx_ && fj < ny_)) return std::nullopt;
  const int i = static_cast<int>(fi), j = static_cast<int>(fj);
  for (int f : buckets_[static_cast<std::size_t>(j * nx_ + i)])
    if (inside_face(f, x, y, p, slopes)) return p;
  return std::nullopt;
}

double SurfaceMesh::nominal_altitude(const SurfacePoint& p) const {
  double z = 0;
  for (int k = 0; k < p.count; ++k) z += p.weights[static_cast<std::size_t>(k)] * nodes_(2, p.nodes[static_cast<std::size_t>(k)]);
  return z;
}

}  // namespace drom::reduce
