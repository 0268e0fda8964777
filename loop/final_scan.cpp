#include "loop/final_scan.hpp"

#include <Eigen/Cholesky>
#include <Eigen/Eigenvalues>
#include <Eigen/Geometry>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <memory>
#include <optional>
#include <random>
#include <stdexcept>
#include <string>

namespace drom::loop {

namespace {

// The upward faces' corners, displaced, with a uniform xy grid over them for the point location.
class DisplacedFaces {
 public:
  struct Hit {
    int face = -1;
    double a = 0, b = 0, z = 0;
    Eigen::Vector2d slope = Eigen::Vector2d::Zero();  // dz/dx, dz/dy of the displaced face there
  };

  DisplacedFaces(const online::FinalShape& shape, const Eigen::Matrix3Xd& displacement, double min_up) {
    if (displacement.cols() != shape.nodes.cols()) throw std::invalid_argument("final scan: one displacement per node");
    const int stride = shape.face_nodes;
    corners_ = stride >= 8 ? 4 : stride == 6 ? 3 : stride;
    if (corners_ != 3 && corners_ != 4) throw std::invalid_argument("final scan: faces of 3, 4, 6 or 8 nodes");
    Eigen::Vector2d lo = Eigen::Vector2d::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    double size = 0;
    for (std::size_t f = 0; f + static_cast<std::size_t>(stride) <= shape.faces.size(); f += static_cast<std::size_t>(stride)) {
      std::array<int, 4> n{};
      for (int k = 0; k < corners_; ++k) n[static_cast<std::size_t>(k)] = shape.faces[f + static_cast<std::size_t>(k)];
      const Eigen::Vector3d x0 = shape.nodes.col(n[0]), x1 = shape.nodes.col(n[1]), xl = shape.nodes.col(n[static_cast<std::size_t>(corners_ - 1)]);
      const Eigen::Vector3d normal = (x1 - x0).cross(xl - x0);
      // Upward by its outward normal (the final part's surface is wound outward). Not either winding,
      // as upward_surface_cloud takes them: the part's bottom, sliding out past the bent top's edge by
      // the in-plane displacement, would be read there through the part, where a laser sees the side.
      if (!(normal.norm() > 0) || normal.z() < min_up * normal.norm()) continue;
      Face face;
      face.nodes = n;
      for (int k = 0; k < corners_; ++k) {
        const int node = n[static_cast<std::size_t>(k)];
        face.x[static_cast<std::size_t>(k)] = shape.nodes.col(node) + displacement.col(node);
        lo = lo.cwiseMin(face.x[static_cast<std::size_t>(k)].head<2>()), hi = hi.cwiseMax(face.x[static_cast<std::size_t>(k)].head<2>());
      }
      size += std::max((x1 - x0).norm(), (xl - x0).norm());
      faces_.push_back(face);
    }
    if (faces_.empty()) return;
    lo_ = lo, hi_ = hi;
    cell_ = std::max(size / static_cast<double>(faces_.size()), 1e-6);
    nx_ = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / cell_)));
    ny_ = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / cell_)));
    grid_.resize(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_));
    for (std::size_t f = 0; f < faces_.size(); ++f) {
      Eigen::Vector2d a = faces_[f].x[0].head<2>(), b = a;
      for (int k = 1; k < corners_; ++k) a = a.cwiseMin(faces_[f].x[static_cast<std::size_t>(k)].head<2>()), b = b.cwiseMax(faces_[f].x[static_cast<std::size_t>(k)].head<2>());
      const auto [i0, j0] = cell(a);
      const auto [i1, j1] = cell(b);
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) grid_[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i)].push_back(static_cast<int>(f));
    }
  }

  int corners() const { return corners_; }
  int count() const { return static_cast<int>(faces_.size()); }
  const std::array<int, 4>& nodes(int face) const { return faces_[static_cast<std::size_t>(face)].nodes; }
  Eigen::Vector2d lo() const { return lo_; }
  Eigen::Vector2d hi() const { return hi_; }

  // The corners' weights at (a, b), in the order upward_surface_cloud uses.
  std::array<double, 4> weights(double a, double b) const {
    if (corners_ == 4) return {(1 - a) * (1 - b), a * (1 - b), a * b, (1 - a) * b};
    return {1 - a - b, a, b, 0};
  }

  // The highest upward face over (x, y), or nothing.
  std::optional<Hit> locate(double x, double y) const {
    if (faces_.empty() || !std::isfinite(x) || !std::isfinite(y)) return std::nullopt;
    const Eigen::Vector2d q(x, y);
    if ((q.array() < lo_.array() - 1e-9).any() || (q.array() > hi_.array() + 1e-9).any()) return std::nullopt;
    const auto [i, j] = cell(q);
    std::optional<Hit> best;
    for (const int f : grid_[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i)]) {
      const auto hit = inside(f, q);
      if (hit && (!best || hit->z > best->z)) best = hit;
    }
    return best;
  }

 private:
  struct Face {
    std::array<int, 4> nodes{};
    std::array<Eigen::Vector3d, 4> x;
  };

  std::pair<int, int> cell(const Eigen::Vector2d& p) const {
    const int i = std::clamp(static_cast<int>(std::floor((p.x() - lo_.x()) / cell_)), 0, nx_ - 1);
    const int j = std::clamp(static_cast<int>(std::floor((p.y() - lo_.y()) / cell_)), 0, ny_ - 1);
    return {i, j};
  }

  // (a, b) of q on face f's xy projection, by Newton on the bilinear map (exact for triangles).
  std::optional<Hit> inside(int f, const Eigen::Vector2d& q) const {
    const auto& x = faces_[static_cast<std::size_t>(f)].x;
    constexpr double slack = 1e-9;
    const double scale = std::max({(x[1] - x[0]).head<2>().norm(), (x[corners_ - 1] - x[0]).head<2>().norm(), 1e-9});
    double a = corners_ == 4 ? 0.5 : 1.0 / 3, b = a;
    Eigen::Vector3d ta, tb;
    for (int it = 0; it < 20; ++it) {
      if (corners_ == 4) {
        ta = (1 - b) * (x[1] - x[0]) + b * (x[2] - x[3]);
        tb = (1 - a) * (x[3] - x[0]) + a * (x[2] - x[1]);
      } else {
        ta = x[1] - x[0], tb = x[2] - x[0];
      }
      const auto w = weights(a, b);
      Eigen::Vector3d p = Eigen::Vector3d::Zero();
      for (int k = 0; k < corners_; ++k) p += w[static_cast<std::size_t>(k)] * x[static_cast<std::size_t>(k)];
      const Eigen::Vector2d r = p.head<2>() - q;
      if (r.norm() < 1e-12 * scale && it > 0) break;
      Eigen::Matrix2d J;
      J << ta.x(), tb.x(), ta.y(), tb.y();
      const double det = J.determinant();
      if (!(std::abs(det) > 0)) return std::nullopt;
      const Eigen::Vector2d d = J.inverse() * r;
      a -= d.x(), b -= d.y();
      if (std::abs(a) > 10 || std::abs(b) > 10) return std::nullopt;  // far outside: not this face
    }
    const bool in = corners_ == 4 ? (a >= -slack && a <= 1 + slack && b >= -slack && b <= 1 + slack) : (a >= -slack && b >= -slack && a + b <= 1 + slack);
    if (!in) return std::nullopt;
    const auto w = weights(a, b);
    Hit h;
    h.face = f, h.a = a, h.b = b;
    for (int k = 0; k < corners_; ++k) h.z += w[static_cast<std::size_t>(k)] * x[static_cast<std::size_t>(k)].z();
    const Eigen::Vector3d n = ta.cross(tb);
    if (!(std::abs(n.z()) > 0)) return std::nullopt;
    h.slope = Eigen::Vector2d(-n.x() / n.z(), -n.y() / n.z());
    return h;
  }

  int corners_ = 4;
  std::vector<Face> faces_;
  Eigen::Vector2d lo_ = Eigen::Vector2d::Zero(), hi_ = Eigen::Vector2d::Zero();
  double cell_ = 1;
  int nx_ = 1, ny_ = 1;
  std::vector<std::vector<int>> grid_;
};

}  // namespace

online::HeightField upward_height_field(const online::FinalShape& shape, const Eigen::Matrix3Xd& displacement, double min_up) {
  auto faces = std::make_shared<const DisplacedFaces>(shape, displacement, min_up);
  return [faces](double x, double y) -> std::optional<double> {
    const auto hit = faces->locate(x, y);
    if (!hit) return std::nullopt;
    return hit->z;
  };
}

FinalScan scan_final_part(const online::HeightField& surface, const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, double top, const online::LaserSheet& sheet,
                          const online::SensorErrors& errors, const FinalScanSettings& s) {
  if (!(s.step > 0) || !std::isfinite(s.step)) throw std::invalid_argument("final scan: the step between profiles must be positive");
  if (!(sheet.length > 0) || sheet.points < 2) throw std::invalid_argument("final scan: the sheet needs a length and two points or more");
  if (!(hi.array() >= lo.array()).all() || !lo.allFinite() || !hi.allFinite() || !std::isfinite(top)) throw std::invalid_argument("final scan: the part's extent is not finite");
  FinalScan out;
  std::mt19937 rng(s.seed);
  // The sheet's extent across the feed (its footprint spans sheet.length along its angle); strips
  // overlap by a tenth so no band is left between them.
  const double a = sheet.angle_deg * M_PI / 180;
  const double across = std::abs(std::sin(a)) * sheet.length;
  if (!(across > 1e-6)) throw std::invalid_argument("final scan: a sheet along the feed (angle 0) sweeps no area");
  const double strip = 0.9 * across;
  const int strips = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / strip)));
  const double along = std::abs(std::cos(a)) * sheet.length / 2;
  const long long profiles = static_cast<long long>(std::ceil((hi.x() - lo.x() + 2 * along) / s.step)) + 1;
  const double first_y = lo.y() + (hi.y() - lo.y()) / 2 - strip * (strips - 1) / 2.0;
  out.points.reserve(static_cast<std::size_t>(strips) * static_cast<std::size_t>(profiles) * static_cast<std::size_t>(sheet.points));
  for (int k = 0; k < strips; ++k)
    for (long long i = 0; i < profiles; ++i) {
      // The emission point's footprint centre at (x, y): the tip is that minus the sheet's offset.
      const Eigen::Vector3d tip(lo.x() - along + static_cast<double>(i) * s.step - sheet.offset.x(), first_y + k * strip - sheet.offset.y(), top + s.clearance);
      const auto profile = online::scan(sheet, errors, tip, tip, surface, rng);
      ++out.profiles;
      for (const auto& p : profile) {
        if (std::isfinite(p.z)) out.points.push_back(p);
        else ++out.no_reading;
      }
    }
  return out;
}

ScanFit fit_final_shape(const online::FinalShape& geometry, const Eigen::MatrixXd& U, const std::vector<online::MeasuredPoint>& points, const FinalScanSettings& s,
                        const ScanPrior* prior) {
  const Eigen::Index n = geometry.nodes.cols(), r = U.cols();
  if (U.rows() != 3 * n) throw std::invalid_argument("final scan: the final-shape basis has " + std::to_string(U.rows()) + " rows, expected 3 x " + std::to_string(n) + " nodes");
  if (r == 0) throw std::invalid_argument("final scan: the final-shape basis has no column");
  Eigen::MatrixXd prior_precision = Eigen::MatrixXd::Zero(r, r);
  double weight = 1;  // 1 / sigma^2 of the scan's heights with a prior; without one, alpha does not depend on it
  ScanFit fit;
  fit.alpha = Eigen::VectorXd::Zero(r);
  if (prior) {
    if (prior->mean.size() != r || prior->covariance.rows() != r || prior->covariance.cols() != r)
      throw std::invalid_argument("final scan: the prior has " + std::to_string(prior->mean.size()) + " coefficients, the basis " + std::to_string(r));
    if (!(prior->noise_sd > 0) || !std::isfinite(prior->noise_sd)) throw std::invalid_argument("final scan: the scan's noise must be positive with a prior");
    if (!prior->mean.allFinite() || !prior->covariance.allFinite()) throw std::invalid_argument("final scan: the prior is not finite");
    // A (near) zero variance is a direction the loop knows (near) exactly: its precision is held large,
    // floored so that the inverse stays finite.
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(prior->covariance);
    const Eigen::VectorXd values = eig.eigenvalues();
    if (values.minCoeff() < -1e-9 * std::max(values.maxCoeff(), 1e-300)) throw std::invalid_argument("final scan: the prior's covariance is not positive semi-definite");
    const double floor = 1e-14 * std::max(values.maxCoeff(), 1e-300);
    Eigen::VectorXd inverse(r);
    for (Eigen::Index k = 0; k < r; ++k) inverse[k] = 1 / std::max(values[k], floor);
    prior_precision = eig.eigenvectors() * inverse.asDiagonal() * eig.eigenvectors().transpose();
    weight = 1 / (prior->noise_sd * prior->noise_sd);
    fit.alpha = prior->mean;  // the relocation starts from the prediction
  }
  double threshold = std::numeric_limits<double>::infinity();
  std::vector<double> magnitudes;
  Eigen::MatrixXd H;
  for (int it = 0; it < std::max(1, s.iterations); ++it) {
    const Eigen::VectorXd u = U * fit.alpha;
    const Eigen::Matrix3Xd displacement = Eigen::Map<const Eigen::Matrix3Xd>(u.data(), 3, n);
    const DisplacedFaces faces(geometry, displacement, s.min_up);
    H = Eigen::MatrixXd::Zero(r, r);
    Eigen::VectorXd g = Eigen::VectorXd::Zero(r), row(r);
    double sum = 0;
    long long used = 0, off = 0, dropped = 0;
    magnitudes.clear();
    for (const auto& m : points) {
      if (!std::isfinite(m.x) || !std::isfinite(m.y) || !std::isfinite(m.z)) { ++off; continue; }
      const auto hit = faces.locate(m.x, m.y);
      if (!hit) { ++off; continue; }
      const double residual = m.z - hit->z;
      magnitudes.push_back(std::abs(residual));
      if (std::abs(residual) > threshold) { ++dropped; continue; }
      // d(height at a fixed xy)/d(alpha_k) = Uz_k - slope . U(x,y)_k, at the point's (a, b).
      const auto w = faces.weights(hit->a, hit->b);
      row.setZero();
      for (int k = 0; k < faces.corners(); ++k) {
        const Eigen::Index node = faces.nodes(hit->face)[static_cast<std::size_t>(k)];
        row += w[static_cast<std::size_t>(k)] * (U.row(3 * node + 2) - hit->slope.x() * U.row(3 * node) - hit->slope.y() * U.row(3 * node + 1)).transpose();
      }
      H.selfadjointView<Eigen::Lower>().rankUpdate(row);
      g += row * residual;
      sum += residual * residual, ++used;
    }
    H = H.selfadjointView<Eigen::Lower>();
    if ((used < r && !prior) || (used == 0 && prior)) throw std::invalid_argument("final scan: " + std::to_string(used) + " usable points for " + std::to_string(r) + " coefficients of the final-shape basis");
    fit.used = used, fit.off_part = off, fit.outliers = dropped;
    fit.residual_rms = used > 0 ? std::sqrt(sum / static_cast<double>(used)) : 0.0;
    // Gauss-Newton on the posterior: (H / sigma^2 + P) step = g / sigma^2 + P (mean - alpha). A
    // whisker of ridge keeps a basis column no reading sees (an in-plane mode) where it is.
    Eigen::MatrixXd A = weight * H + prior_precision;
    A.diagonal().array() += 1e-12 * std::max(A.diagonal().maxCoeff(), 1e-300);
    Eigen::VectorXd b = weight * g;
    if (prior) b += prior_precision * (prior->mean - fit.alpha);
    fit.alpha += A.ldlt().solve(b);
    fit.iterations = it + 1;
    // From the second iteration on (the first starts from the drawn part or the loop's estimate, its
    // residuals may be the whole distortion) the outliers are judged on a robust scale, the residuals'
    // median absolute deviation: chips would inflate an RMS and hide behind it. Floored at 0.1 µm so
    // that a noiseless scan does not call the model's own misfit outliers.
    if (it >= 1 && !magnitudes.empty()) {
      const auto middle = magnitudes.begin() + static_cast<std::ptrdiff_t>(magnitudes.size() / 2);
      std::nth_element(magnitudes.begin(), middle, magnitudes.end());
      threshold = s.outlier_sigmas * std::max(1.4826 * *middle, 1e-4);
    }
  }
  // The covariance at the solution (the last iteration's H): without a prior, the residual RMS as
  // the noise; with one, the posterior's. A direction the readings do not see (an in-plane mode
  // under a height scan) and no prior holds is counted, and left out of the covariance (its
  // coefficient stays where it started) rather than given the ridge's meaningless variance.
  const Eigen::MatrixXd A = (prior ? weight : 1.0) * H + prior_precision;
  const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eig(A);
  const Eigen::VectorXd values = eig.eigenvalues();
  const double seen = 1e-10 * std::max(values.maxCoeff(), 1e-300);
  Eigen::VectorXd inverse = Eigen::VectorXd::Zero(r);
  for (Eigen::Index k = 0; k < r; ++k) {
    if (values[k] > seen) inverse[k] = 1 / values[k];
    else ++fit.unobserved;
  }
  fit.covariance = eig.eigenvectors() * inverse.asDiagonal() * eig.eigenvectors().transpose();
  if (!prior) fit.covariance *= fit.residual_rms * fit.residual_rms;
  fit.shape = geometry;
  const Eigen::VectorXd u = U * fit.alpha;
  fit.shape.displacement = Eigen::Map<const Eigen::Matrix3Xd>(u.data(), 3, n);
  const Eigen::MatrixXd UC = U * fit.covariance;
  const Eigen::VectorXd var = UC.cwiseProduct(U).rowwise().sum();
  fit.shape.sd = Eigen::Map<const Eigen::Matrix3Xd>(var.cwiseMax(0).cwiseSqrt().eval().data(), 3, n);
  return fit;
}

double max_upward_difference(const online::FinalShape& geometry, const Eigen::Matrix3Xd& a, const Eigen::Matrix3Xd& b, double min_up) {
  if (a.cols() != geometry.nodes.cols() || b.cols() != geometry.nodes.cols()) throw std::invalid_argument("max_upward_difference: one displacement per node");
  const DisplacedFaces faces(geometry, Eigen::Matrix3Xd::Zero(3, geometry.nodes.cols()), min_up);
  double worst = 0;
  for (int f = 0; f < faces.count(); ++f)
    for (int k = 0; k < faces.corners(); ++k) {
      const int node = faces.nodes(f)[static_cast<std::size_t>(k)];
      worst = std::max(worst, (a.col(node) - b.col(node)).norm());
    }
  return worst;
}

}  // namespace drom::loop
