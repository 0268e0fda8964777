#include "online/predictor.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace drom::online {

namespace {
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
}

const char* verdict_name(Verdict v) {
  switch (v) {
    case Verdict::WithinTolerance: return "within tolerance";
    case Verdict::StraighteningNeeded: return "straightening needed";
    case Verdict::Scrap: break;
  }
  return "scrap";
}

Predictor::Predictor(reduce::LightModel model, PredictorSettings settings) : model_(std::move(model)), settings_(settings), r_(model_.rank()) {
  if (!(settings_.noise_sd > 0) || !(settings_.prior_scale > 0) || !(settings_.path_sample > 0) || settings_.learning_window < 1)
    throw std::invalid_argument("predictor settings: noise_sd, prior_scale and path_sample must be > 0, learning_window >= 1");
  const int n = model_.target.node_count();
  // U1_k at each node's cut time: the reference of the differenced basis.
  cut_values_.setZero(n, r_);
  for (int k = 0; k < r_; ++k) {
    const auto& h = model_.histories[static_cast<std::size_t>(k)];
    for (int i = 0; i < n; ++i)
      if (std::isfinite(model_.target_cut_time[i])) cut_values_(i, k) = h.at(i, model_.target_cut_time[i]);
  }
  prior_precision_ = (settings_.prior_scale * model_.prior_sd).array().square().inverse();
  // A face is cut when its last node is (never, if one of them never is).
  face_cut_time_.assign(static_cast<std::size_t>(model_.target.face_count()), 0.0);
  for (int f = 0; f < model_.target.face_count(); ++f)
    for (int q = 0; q < model_.target.nodes_per_face(); ++q)
      face_cut_time_[static_cast<std::size_t>(f)] = std::max(face_cut_time_[static_cast<std::size_t>(f)],
                                                             model_.target_cut_time[model_.target.faces()[static_cast<std::size_t>(f * model_.target.nodes_per_face() + q)]]);
  node_stamp_.assign(static_cast<std::size_t>(n), 0);
  face_stamp_.assign(static_cast<std::size_t>(model_.target.face_count()), 0);
  face_slot_.assign(static_cast<std::size_t>(model_.target.face_count()), -1);
  node_delta_.setZero(n, r_);
  for (const auto& h : model_.histories) {
    if (h.times().size() != model_.histories.front().times().size() || h.times() != model_.histories.front().times())
      throw std::invalid_argument("predictor: the model's histories must share their instants");
    interval_factors_.emplace_back(h.terms());
    interval_factors_.emplace_back(h.terms());
    space_by_node_.emplace_back(h.space().transpose());  // a node's terms contiguous: one cache line, not one per term
  }
  node_cached_.assign(static_cast<std::size_t>(n), 0);
  node_lo_.setZero(n, r_);
  node_hi_.setZero(n, r_);
  normal_ = Eigen::MatrixXd::Zero(r_, r_);
  rhs_ = Eigen::VectorXd::Zero(r_);

  // Path samples: every path_sample mm along the programmed path (and at every waypoint).
  std::vector<double> times;
  std::vector<Eigen::Vector3d> where;
  const auto& path = model_.path;
  for (Eigen::Index i = 0; i < path.rows(); ++i) {
    const int pieces = i + 1 < path.rows() ? std::max(1, static_cast<int>(std::ceil((path.row(i + 1).head<2>() - path.row(i).head<2>()).norm() / settings_.path_sample))) : 1;
    for (int p = 0; p < pieces; ++p) {
      const double a = static_cast<double>(p) / pieces;
      const Eigen::RowVector4d q = i + 1 < path.rows() ? Eigen::RowVector4d((1 - a) * path.row(i) + a * path.row(i + 1)) : Eigen::RowVector4d(path.row(i));
      if (!times.empty() && q[3] <= times.back()) continue;
      times.push_back(q[3]);
      where.emplace_back(q[0], q[1], q[2]);
    }
  }
  const auto m = static_cast<Eigen::Index>(times.size());
  sample_time_ = Eigen::Map<Eigen::VectorXd>(times.data(), m);
  sample_w_.setZero(m, r_), sample_wx_.setZero(m, r_), sample_wy_.setZero(m, r_);
  sample_inside_.setZero(m), sample_s0x_.setZero(m), sample_s0y_.setZero(m);
  for (Eigen::Index j = 0; j < m; ++j) {
    const auto p = model_.target.locate(where[static_cast<std::size_t>(j)].x(), where[static_cast<std::size_t>(j)].y());
    if (!p) continue;
    sample_inside_[j] = 1;
    for (int k = 0; k < r_; ++k) {
      const Eigen::VectorXd b = model_.histories[static_cast<std::size_t>(k)].time_factors(times[static_cast<std::size_t>(j)]);
      const auto& a = model_.histories[static_cast<std::size_t>(k)].space();
      for (int q = 0; q < p->count; ++q) {
        const double u = a.row(p->nodes[static_cast<std::size_t>(q)]).dot(b);
        sample_w_(j, k) += p->weights[static_cast<std::size_t>(q)] * u;
        sample_wx_(j, k) += p->dx[static_cast<std::size_t>(q)] * u;
        sample_wy_(j, k) += p->dy[static_cast<std::size_t>(q)] * u;
      }
    }
    for (int q = 0; q < p->count; ++q) {
      const double z = model_.target.nodes()(2, p->nodes[static_cast<std::size_t>(q)]);
      sample_s0x_[j] += p->dx[static_cast<std::size_t>(q)] * z;
      sample_s0y_[j] += p->dy[static_cast<std::size_t>(q)] * z;
    }
  }
  snapshot_.store(std::make_shared<const Snapshot>(Snapshot{Eigen::VectorXd::Zero(r_), false}));
}

double Predictor::applied_offset_at(double t) const {
  // The offset in force at t: the last one recorded at or before t (none before the first: 0).
  auto it = std::upper_bound(offsets_.begin(), offsets_.end(), t, [](double v, const auto& e) { return v < e.first; });
  return it == offsets_.begin() ? 0.0 : std::prev(it)->second;
}

void Predictor::set_offset(double t, double offset) {
  // The history stays sorted by time; an entry only where the offset in force changes.
  if (applied_offset_at(t) == offset) return;
  const auto at = std::upper_bound(offsets_.begin(), offsets_.end(), t, [](double v, const auto& e) { return v < e.first; });
  offsets_.emplace(at, t, offset);
}

void Predictor::record_offset(double t, double offset) {
  std::lock_guard<std::mutex> lock(ingest_);
  if (!std::isfinite(t) || !std::isfinite(offset)) throw std::invalid_argument("record_offset: time and offset must be finite");
  set_offset(t, offset);
}

ProfileReport Predictor::add_profile(double t, const ToolPose& pose, std::span<const MeasuredPoint> points) {
  ProfileReport report;
  std::lock_guard<std::mutex> lock(ingest_);
  if (!std::isfinite(t) || !std::isfinite(pose.applied_offset)) throw std::invalid_argument("add_profile: the profile's time or offset is not finite");
  if (profiles_ > 0 && t < last_profile_time_) throw std::invalid_argument("add_profile: profiles must come in time order");
  last_profile_time_ = t;
  set_offset(t, pose.applied_offset);
  const auto snap = snapshot();

  // The profile's time factors once, then the differenced basis per touched node, then per face the
  // sums of N N^T and N m: the normal equations get D_f^T (sum N N^T) D_f per face, not per point.
  // Scratch arrays are members, stamped per profile, so nothing is allocated per point.
  if (++stamp_ == 0) {
    std::fill(node_stamp_.begin(), node_stamp_.end(), 0);
    std::fill(face_stamp_.begin(), face_stamp_.end(), 0);
    stamp_ = 1;
  }
  // U1(node, t) is linear in t between two stored instants: each node's values at the interval's two
  // ends are computed once (r x terms each) and kept while profiles stay in that interval (tens of
  // profiles at 10 Hz), so a profile pays r per node, not r x terms.
  const auto interval = r_ > 0 ? reduce::locate_time(model_.histories.front().times(), t) : reduce::TimeInterval{};
  if (r_ > 0 && model_.histories.front().times().size() > 1 && interval.i != cached_interval_) {
    cached_interval_ = interval.i;
    std::fill(node_cached_.begin(), node_cached_.end(), 0);
    for (int k = 0; k < r_; ++k) {
      const auto& T = model_.histories[static_cast<std::size_t>(k)].time();
      interval_factors_[static_cast<std::size_t>(2 * k)] = T.row(interval.i).transpose();
      interval_factors_[static_cast<std::size_t>(2 * k + 1)] = T.row(interval.i + 1).transpose();
    }
  }
  touched_.clear();
  const bool offset_varies = !offsets_.empty();  // otherwise 0 everywhere: no need for t_cut
  double square_error = 0;
  int hint = -1;  // consecutive points of a profile mostly share a face
  for (const auto& pt : points) {
    if (!std::isfinite(pt.x) || !std::isfinite(pt.y) || !std::isfinite(pt.z)) {
      ++report.invalid;
      continue;
    }
    const auto p = model_.target.locate(pt.x, pt.y, hint, false);
    if (!p) {
      ++report.outside;
      continue;
    }
    hint = p->face;
    // The differenced basis needs every node of the face already cut.
    if (!(face_cut_time_[p->face] <= t)) {
      ++report.not_yet_cut;
      continue;
    }
    double offset = 0;
    if (offset_varies) {
      double t_cut = 0;
      for (int q = 0; q < p->count; ++q) t_cut += p->weights[static_cast<std::size_t>(q)] * model_.target_cut_time[p->nodes[static_cast<std::size_t>(q)]];
      offset = applied_offset_at(t_cut);
    }
    const double m = pt.z - (model_.target.nominal_altitude(*p) + offset);
    if (std::abs(m) > settings_.reading_range) {
      ++report.out_of_range;
      continue;
    }
    FaceSums* f;
    if (face_stamp_[static_cast<std::size_t>(p->face)] != stamp_) {
      face_stamp_[static_cast<std::size_t>(p->face)] = stamp_;
      face_slot_[static_cast<std::size_t>(p->face)] = static_cast<int>(touched_.size());
      if (touched_.size() == face_sums_.size()) face_sums_.emplace_back();
      touched_.push_back(p->face);
      f = &face_sums_[touched_.size() - 1];
      f->face = *p;
      f->NN.setZero();
      f->Nm.setZero();
      for (int q = 0; q < p->count; ++q) {
        const int node = p->nodes[static_cast<std::size_t>(q)];
        if (node_stamp_[static_cast<std::size_t>(node)] != stamp_) {
          node_stamp_[static_cast<std::size_t>(node)] = stamp_;
          if (!node_cached_[static_cast<std::size_t>(node)]) {
            node_cached_[static_cast<std::size_t>(node)] = 1;
            for (int k = 0; k < r_; ++k) {
              const auto a = space_by_node_[static_cast<std::size_t>(k)].col(node);
              node_lo_(node, k) = a.dot(interval_factors_[static_cast<std::size_t>(2 * k)]);
              node_hi_(node, k) = a.dot(interval_factors_[static_cast<std::size_t>(2 * k + 1)]);
            }
          }
          node_delta_.row(node) = (1 - interval.weight) * node_lo_.row(node) + interval.weight * node_hi_.row(node) - cut_values_.row(node);
        }
        f->predicted[q] = node_delta_.row(node).dot(snap->alpha);
      }
      for (int q = p->count; q < 9; ++q) f->predicted[q] = 0;
    } else {
      f = &face_sums_[static_cast<std::size_t>(face_slot_[static_cast<std::size_t>(p->face)])];
    }
    const Eigen::Map<const Eigen::Matrix<double, 9, 1>> N(p->weights.data());  // zero past p->count
    f->NN.noalias() += N * N.transpose();
    f->Nm += N * m;
    const double e = m - N.dot(f->predicted);
    square_error += e * e;
    ++report.used;
  }
  const double w = 1 / (settings_.noise_sd * settings_.noise_sd);
  for (std::size_t i = 0; i < touched_.size(); ++i) {
    const FaceSums& f = face_sums_[i];
    const int c = f.face.count;
    Eigen::MatrixXd D(c, r_);
    for (int q = 0; q < c; ++q) D.row(q) = node_delta_.row(f.face.nodes[static_cast<std::size_t>(q)]);
    normal_.noalias() += w * (D.transpose() * f.NN.topLeftCorner(c, c) * D);
    rhs_.noalias() += w * (D.transpose() * f.Nm.head(c));
  }
  points_ += report.used;
  ++profiles_;
  report.predictive_rms = report.used > 0 ? std::sqrt(square_error / report.used) : 0;

  // Learning: the fit, before seeing them, predicted the recent profiles' points to within the
  // tolerance (net of the sensor noise), with at least 3 points per unknown behind it.
  if (report.used > 0) {
    recent_square_error_.push_back(square_error);
    recent_count_.push_back(report.used);
    if (static_cast<int>(recent_count_.size()) > settings_.learning_window) {
      recent_square_error_.erase(recent_square_error_.begin());
      recent_count_.erase(recent_count_.begin());
    }
  }
  if (!learned_ && static_cast<int>(recent_count_.size()) == settings_.learning_window && points_ >= 3LL * r_) {
    double se = 0, count = 0;
    for (std::size_t i = 0; i < recent_count_.size(); ++i) se += recent_square_error_[i], count += recent_count_[i];
    const double net = std::sqrt(std::max(0.0, se / count - settings_.noise_sd * settings_.noise_sd));
    learned_ = net <= settings_.learning_tolerance;
  }
  Eigen::MatrixXd precision = normal_;
  precision.diagonal() += prior_precision_;
  snapshot_.store(std::make_shared<const Snapshot>(Snapshot{precision.llt().solve(rhs_), learned_}), std::memory_order_release);
  return report;
}

Estimate Predictor::estimate() const {
  std::lock_guard<std::mutex> lock(ingest_);
  Eigen::MatrixXd precision = normal_;
  precision.diagonal() += prior_precision_;
  const Eigen::LLT<Eigen::MatrixXd> llt(precision);
  Estimate e;
  e.alpha = llt.solve(rhs_);
  e.covariance = llt.solve(Eigen::MatrixXd::Identity(r_, r_));
  e.points = points_;
  e.profiles = profiles_;
  e.learned = learned_;
  return e;
}

Eigen::RowVectorXd Predictor::basis_at(const reduce::SurfacePoint& p, double t) const {
  Eigen::RowVectorXd u = Eigen::RowVectorXd::Zero(r_);
  for (int k = 0; k < r_; ++k) {
    const auto& h = model_.histories[static_cast<std::size_t>(k)];
    const Eigen::VectorXd b = h.time_factors(t);
    for (int q = 0; q < p.count; ++q) u[k] += p.weights[static_cast<std::size_t>(q)] * h.space().row(p.nodes[static_cast<std::size_t>(q)]).dot(b);
  }
  return u;
}

double Predictor::target_altitude(double x, double y, double t) const {
  const auto p = model_.target.locate(x, y);
  if (!p) return kNaN;
  return model_.target.nominal_altitude(*p) + basis_at(*p, t).dot(snapshot()->alpha);
}

double Predictor::target_altitude_sd(double x, double y, double t) const {
  const auto p = model_.target.locate(x, y);
  if (!p) return kNaN;
  const Eigen::RowVectorXd u = basis_at(*p, t);
  return std::sqrt(std::max(0.0, u.dot(estimate().covariance * u.transpose())));
}

double Predictor::predicted_offset(double t) const {
  const auto snap = snapshot();
  if (!snap->learned || sample_time_.size() == 0) return 0;
  const auto [j, a] = reduce::locate_time(sample_time_, t);
  if (sample_time_.size() == 1) return sample_inside_[0] ? sample_w_.row(0).dot(snap->alpha) : 0.0;
  auto at = [&](Eigen::Index i) {
    if (sample_inside_[i] == 0) return 0.0;
    const double w = sample_w_.row(i).dot(snap->alpha);
    if (model_.tool_shape != reduce::ToolShape::Ball) return w;
    const double gx = sample_wx_.row(i).dot(snap->alpha), gy = sample_wy_.row(i).dot(snap->alpha);
    const double sx = sample_s0x_[i], sy = sample_s0y_[i];
    return w + model_.tool_radius * (std::sqrt(1 + (sx + gx) * (sx + gx) + (sy + gy) * (sy + gy)) - std::sqrt(1 + sx * sx + sy * sy));
  };
  return (1 - a) * at(j) + a * at(j + 1);
}

double Predictor::tool_offset(double t) {
  const double target = predicted_offset(t);
  if (!offset_started_) {
    offset_started_ = true;
    last_offset_time_ = t;
  }
  const double step = settings_.max_offset_rate * std::abs(t - last_offset_time_);
  last_offset_ += std::clamp(target - last_offset_, -step, step);
  last_offset_time_ = t;
  return last_offset_;
}

FinalShape Predictor::final_shape() const {
  const Estimate e = estimate();
  FinalShape s;
  s.nodes = model_.shape_nodes;
  s.faces = model_.shape_faces;
  s.face_nodes = model_.shape_face_nodes;
  const Eigen::Index n = model_.shape_nodes.cols();
  const Eigen::VectorXd u = model_.final_basis * e.alpha;
  const Eigen::MatrixXd UC = model_.final_basis * e.covariance;
  const Eigen::VectorXd var = UC.cwiseProduct(model_.final_basis).rowwise().sum();
  s.displacement = Eigen::Map<const Eigen::Matrix3Xd>(u.data(), 3, n);
  s.sd = Eigen::Map<const Eigen::Matrix3Xd>(var.cwiseMax(0).cwiseSqrt().eval().data(), 3, n);
  return s;
}

Verdict Predictor::verdict(const ShapeTolerances& tol) const {
  // On the normal (z) displacement of the final surface: within tolerance if even the pessimistic
  // bound stays inside; scrap if even the optimistic one passes the straightening limit.
  const FinalShape s = final_shape();
  const Eigen::ArrayXd w = s.displacement.row(2).transpose().array().abs(), sd = s.sd.row(2).transpose().array();
  if ((w + tol.confidence * sd).maxCoeff() <= tol.tolerance) return Verdict::WithinTolerance;
  if ((w - tol.confidence * sd).maxCoeff() > tol.straightening_limit) return Verdict::Scrap;
  return Verdict::StraighteningNeeded;
}

}  // namespace drom::online
