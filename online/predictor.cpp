#include "online/predictor.hpp"

#include <Eigen/Cholesky>

#include <algorithm>
#include <cstring>
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
  if (model_.prior_covariance.size() > 0) {
    const Eigen::LLT<Eigen::MatrixXd> llt(settings_.prior_scale * settings_.prior_scale * model_.prior_covariance);
    if (llt.info() != Eigen::Success) throw std::invalid_argument("predictor: the model's prior covariance is not positive definite");
    prior_precision_ = llt.solve(Eigen::MatrixXd::Identity(r_, r_));
  } else {
    prior_precision_ = (settings_.prior_scale * model_.prior_sd).array().square().inverse().matrix().asDiagonal();
  }
  const Eigen::VectorXd prior_mean = model_.prior_mean.size() == r_ ? model_.prior_mean : Eigen::VectorXd::Zero(r_);
  prior_rhs_ = prior_precision_ * prior_mean;
  // The same rule as the model's per-node cut times (drom reduce): the tip down within 2 % of the
  // depth of the point's nominal altitude.
  cut_index_ = reduce::CutTimeIndex(model_.path, model_.tool_radius, 0.02 * model_.pocket_depth,
                                    model_.target.node_count() > 0 ? model_.target.nodes().row(2).maxCoeff() + 0.02 * model_.pocket_depth : 0.0);
  for (const auto* hs : {&model_.histories, &model_.top_histories})
    for (const auto& h : *hs)
      if (h.times().size() != model_.histories.front().times().size() || h.times() != model_.histories.front().times())
        throw std::invalid_argument("predictor: the model's histories must share their instants");
  target_cache_.reset(model_.histories, n);
  if (model_.has_top()) {
    if (static_cast<int>(model_.top_histories.size()) != r_ || model_.top_cut_time.size() != model_.top.node_count())
      throw std::invalid_argument("predictor: the model's top needs one history per mode and a cut time per node");
    top_cache_.reset(model_.top_histories, model_.top.node_count());
    const double top_sd = settings_.top_noise_sd > 0 ? settings_.top_noise_sd : settings_.noise_sd;
    top_weight_ = settings_.noise_sd / top_sd;
  }
  normal_ = Eigen::MatrixXd::Zero(r_, r_);
  rhs_ = Eigen::VectorXd::Zero(r_);
  kept_ = Share::zero(r_);

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
  const Eigen::MatrixXd prior_covariance = prior_precision_.llt().solve(Eigen::MatrixXd::Identity(r_, r_));
  snapshot_.store(std::make_shared<const Snapshot>(Snapshot{prior_mean, prior_covariance, false}));
  // The sane bound on the commanded offset: what the prior finds plausible anywhere on the path, its
  // mean plus four standard deviations (a ball end mill's normal offset changes it by a fraction).
  max_offset_ = settings_.max_offset;
  if (!(max_offset_ > 0)) {
    max_offset_ = 0;
    for (Eigen::Index j = 0; j < m; ++j) {
      if (sample_inside_[j] == 0) continue;
      const Eigen::RowVectorXd g = offset_gradient(j, prior_mean);
      const double mean = g.dot(prior_mean), variance = g.dot(prior_covariance * g.transpose());
      // The model reader bounds every number so that these stay finite; a bound that is not would let
      // any offset through (and std::max would quietly drop a NaN), so it is refused here too.
      if (!std::isfinite(mean) || !std::isfinite(variance)) throw std::invalid_argument("predictor: the model's prior gives no finite bound on the commanded offset");
      max_offset_ = std::max(max_offset_, std::abs(mean) + 4 * std::sqrt(std::max(0.0, variance)));
    }
  }
}

Predictor::Share& Predictor::Share::operator+=(const Share& o) {
  normal += o.normal;
  rhs += o.rhs;
  points += o.points;
  profiles += o.profiles;
  return *this;
}

Predictor::Share Predictor::Share::zero(int r) {
  Share s;
  s.normal.setZero(r, r);
  s.rhs.setZero(r);
  return s;
}

Rejections Predictor::rejections() const {
  std::lock_guard<std::mutex> lock(ingest_);
  Rejections r = rejections_;
  r.offsets_clamped = offsets_clamped_.load();
  return r;
}

void Predictor::enter_face(InstantCache& cache, const reduce::SurfacePoint& p, const reduce::TimeInterval& now, FaceMemo& memo) {
  memo.face = p.face;
  memo.w.clear();
  for (auto& c : memo.cut) c.instant = -1;
  memo.rows_now.setZero(p.count, r_);
  if (r_ == 0) return;
  const Eigen::Index next = next_instant(now.i);
  for (int q = 0; q < p.count; ++q) {
    const int node = p.nodes[static_cast<std::size_t>(q)];
    const double* a = cache.at(node, now.i);
    const double* b = cache.at(node, next);
    double* row = memo.rows_now.row(q).data();
    for (int k = 0; k < r_; ++k) row[k] = (1 - now.weight) * a[k] + now.weight * b[k];
  }
}

void Predictor::FaceMemo::row_at(const reduce::SurfacePoint& p, double* out) const {
  // By hand: at r ~ 20 Eigen's runtime-sized product costs more in dispatch than in arithmetic.
  const Eigen::Index r = rows_now.cols();
  std::fill(out, out + r, 0.0);
  for (int q = 0; q < p.count; ++q) {
    const double N = p.weights[static_cast<std::size_t>(q)];
    const double* row = rows_now.row(q).data();
    for (Eigen::Index k = 0; k < r; ++k) out[k] += N * row[k];
  }
}

const double* Predictor::face_w(FaceMemo& memo, const reduce::SurfacePoint& p, Eigen::Index j, const Eigen::VectorXd& alpha) {
  for (auto it = memo.w.rbegin(); it != memo.w.rend(); ++it)  // the latest first: a face's points mostly ask for the same few
    if (it->first == j) return it->second.data();
  auto& [instant, w] = memo.w.emplace_back();
  instant = j;
  for (int q = 0; q < p.count; ++q) w[static_cast<std::size_t>(q)] = Eigen::Map<const Eigen::VectorXd>(target_cache_.at(p.nodes[static_cast<std::size_t>(q)], j), r_).dot(alpha);
  return w.data();
}

Eigen::Index Predictor::next_instant(Eigen::Index i) const { return i + (model_.histories.front().times().size() > 1 ? 1 : 0); }

const Predictor::FaceMemo::CutRows& Predictor::cut_rows(FaceMemo& memo, const reduce::SurfacePoint& p, Eigen::Index i) {
  for (const auto& c : memo.cut)
    if (c.instant == i) return c;
  auto& c = memo.cut[memo.older];
  memo.older = 1 - memo.older;
  c.instant = i;
  c.since.resize(p.count, r_);
  c.step.resize(p.count, r_);
  const Eigen::Index next = next_instant(i);
  for (int q = 0; q < p.count; ++q) {
    const int node = p.nodes[static_cast<std::size_t>(q)];
    const double* a = target_cache_.at(node, i);
    const double* b = target_cache_.at(node, next);
    const double* now = memo.rows_now.row(q).data();
    double* since = c.since.row(q).data();
    double* step = c.step.row(q).data();
    for (int k = 0; k < r_; ++k) since[k] = now[k] - a[k], step[k] = b[k] - a[k];
  }
  return c;
}

void Predictor::InstantCache::reset(const std::vector<reduce::SpaceTimeField>& h, int nodes) {
  space_by_node.clear();
  time_by_instant.clear();
  for (const auto& f : h) {
    space_by_node.emplace_back(f.space().transpose());  // a node's terms contiguous: one cache line, not one per term
    time_by_instant.emplace_back(f.time().transpose());  // an instant's terms contiguous too: the fill is one vectorized dot
  }
  values.setZero(static_cast<Eigen::Index>(h.size()), static_cast<Eigen::Index>(nodes) * kSlots);
  tag.assign(static_cast<std::size_t>(nodes) * kSlots, -1);
}

const double* Predictor::InstantCache::at(int node, Eigen::Index j) {
  const std::size_t slot = static_cast<std::size_t>(node) * kSlots + static_cast<std::size_t>(j % kSlots);
  double* v = values.col(static_cast<Eigen::Index>(slot)).data();
  if (tag[slot] != j) {
    tag[slot] = j;
    for (std::size_t k = 0; k < space_by_node.size(); ++k) v[k] = space_by_node[k].col(node).dot(time_by_instant[k].col(j));
  }
  return v;
}

double Predictor::applied_offset_at(double t) const { return offsets_.at(t); }

void Predictor::set_offset(double t, double offset) { offsets_.set(t, offset); }

void Predictor::record_offset(double t, double offset) {
  std::lock_guard<std::mutex> lock(ingest_);
  if (!std::isfinite(t) || !std::isfinite(offset)) {
    ++rejections_.offsets_non_finite;
    return;
  }
  // A late record is still a fact about the machine: the offset was in force from t on.
  if (t < last_record_time_) ++rejections_.offsets_late;
  last_record_time_ = std::max(last_record_time_, t);
  set_offset(t, offset);
}

ProfileReport Predictor::add_profile(double t, const ToolPose& pose, std::span<const MeasuredPoint> points) {
  ProfileReport report;
  std::lock_guard<std::mutex> lock(ingest_);
  auto reject = [&](long long& count, const char* why) {
    ++count;
    report.rejected = why;
    return report;
  };
  if (!std::isfinite(t) || !std::isfinite(pose.applied_offset) || !pose.tip.allFinite()) return reject(rejections_.non_finite, "non-finite time, offset or tool position");
  if (seen_profile_ && t < last_profile_time_) return reject(rejections_.out_of_order, "older than the last profile");
  if (seen_profile_ && t == last_profile_time_) return reject(rejections_.repeated, "at the time of the last profile");
  seen_profile_ = true;
  last_profile_time_ = t;
  set_offset(t, pose.applied_offset);
  if (!points.empty() && points.size() == last_points_.size() && std::memcmp(points.data(), last_points_.data(), points.size_bytes()) == 0)
    return reject(rejections_.stuck, "the very same points as the last profile (a frozen sensor)");
  last_points_.assign(points.begin(), points.end());
  const auto snap = snapshot();

  // Per point, the differenced basis g = U1(x, t) - U1(x, t_cut(x)) at the point's own cut time; U1 is
  // linear in time between stored instants, so both terms are blends of nodal values at instants,
  // which the per-node cache serves (the first per face, FaceMemo). The normal equations then get
  // G^T G in one rank update.
  const Eigen::VectorXd no_instants;
  const Eigen::VectorXd& instants = r_ > 0 ? model_.histories.front().times() : no_instants;
  const reduce::TimeInterval now = reduce::locate_time(instants, t);
  if (G_.rows() < static_cast<Eigen::Index>(points.size())) {
    G_.resize(static_cast<Eigen::Index>(points.size()), r_);
    m_.resize(static_cast<Eigen::Index>(points.size()));
  }
  // Which cut left the floor depends on w, so on the fit: the points are gathered with the current
  // fit's picks. While still learning, the fit moves a lot from profile to profile, and a wrong pick
  // would stay in the normal equations for good: the profile is then gathered again with the fit it
  // leads to, until the picks settle (at most three times).
  double square_error = 0;
  Eigen::Index used = 0;
  const bool use_top = settings_.use_stock_top && model_.has_top();
  // The row in G_.row(used) and its reading m, kept unless it is not the surface the row models (a
  // wall, the other surface, a glitch): far from what the fit expects there. Against the fit, not
  // against the commanded altitude: late in a run the floor has moved by more than the range since
  // it was cut, and a cut at the range would keep only the readings whose noise pulls them inside it.
  auto keep = [&](double m, double scale, const Eigen::VectorXd& alpha) {
    auto g = G_.row(used);
    if (std::abs(m - g.dot(alpha)) > settings_.reading_range) {
      ++report.out_of_range;
      return false;
    }
    const double e = m - g.dot(snap->alpha);
    square_error += e * e;
    if (scale != 1.0) g *= scale;
    m_[used++] = scale * m;
    return true;
  };
  auto gather = [&](const Eigen::VectorXd& alpha) {
    report = ProfileReport{};
    square_error = 0;
    used = 0;
    floor_memo_.face = top_memo_.face = -1;  // w in the memo belongs to the fit it was gathered with
    int hint = -1, top_hint = -1;            // consecutive points of a profile mostly share a face
    for (const auto& pt : points) {
      if (!std::isfinite(pt.x) || !std::isfinite(pt.y) || !std::isfinite(pt.z)) {
        ++report.invalid;
        continue;
      }
      const auto p = model_.target.locate(pt.x, pt.y, hint, false);
      double s0 = 0;
      if (p) {
        hint = p->face;
        s0 = model_.target.nominal_altitude(*p);
        cut_index_.covers({pt.x, pt.y, s0}, t, covers_);
      }
      if (!p || covers_.empty()) {
        // Not the machined floor: the stock's top, if the tool has been near none of its face's nodes.
        const auto q = use_top ? model_.top.locate(pt.x, pt.y, top_hint, false) : std::nullopt;
        if (q) top_hint = q->face;
        if (!q || !reduce::face_uncut(*q, model_.top_cut_time, t)) {
          ++(p ? report.not_yet_cut : report.outside);
          continue;
        }
        if (q->face != top_memo_.face) enter_face(top_cache_, *q, now, top_memo_);
        top_memo_.row_at(*q, G_.row(used).data());
        // One weight in the normal equations: the row carries sigma_floor / sigma_top.
        if (keep(pt.z - model_.top.nominal_altitude(*q), top_weight_, alpha)) ++report.used_top;
        continue;
      }
      if (p->face != floor_memo_.face) enter_face(target_cache_, *p, now, floor_memo_);
      // w at this point at instant j, from its face's nodal values.
      auto w_instant = [&](Eigen::Index j) {
        const double* w = face_w(floor_memo_, *p, j, alpha);
        double sum = 0;
        for (int q = 0; q < p->count; ++q) sum += p->weights[static_cast<std::size_t>(q)] * w[q];
        return sum;
      };
      // The cut that left the floor here, by the current fit (the fit is linear between the model's
      // instants, as the truth is between its stations).
      const reduce::LowestCut cut = reduce::lowest_cut(
          covers_, instants, offsets_,
          [&](double, reduce::TimeInterval at) {
            if (r_ == 0) return 0.0;
            const double a = w_instant(at.i);
            return at.weight == 0 ? a : (1 - at.weight) * a + at.weight * w_instant(at.i + 1);
          },
          candidates_, 1e-12);
      // g = sum_q N_q (U1(t) - U1(i) - c (U1(i + 1) - U1(i))) at the face's nodes, c the cut's weight in (i, i + 1).
      double* g = G_.row(used).data();
      std::fill(g, g + r_, 0.0);
      if (r_ > 0) {
        const FaceMemo::CutRows& rows = cut_rows(floor_memo_, *p, cut.at.i);
        const double c = cut.at.weight;
        for (int q = 0; q < p->count; ++q) {
          const double N = p->weights[static_cast<std::size_t>(q)], Nc = N * c;
          const double* since = rows.since.row(q).data();
          const double* step = rows.step.row(q).data();
          for (int k = 0; k < r_; ++k) g[k] += N * since[k] - Nc * step[k];
        }
      }
      keep(pt.z - (s0 + cut.offset), 1.0, alpha);
    }
  };
  const double w = 1 / (settings_.noise_sd * settings_.noise_sd);
  auto solve_with_profile = [&] {
    const auto G = G_.topRows(used);
    Eigen::MatrixXd precision = normal_;
    precision.selfadjointView<Eigen::Lower>().rankUpdate(G.transpose(), w);
    precision += prior_precision_;
    return Eigen::VectorXd(precision.selfadjointView<Eigen::Lower>().llt().solve(rhs_ + prior_rhs_ + w * (G.transpose() * m_.head(used))));
  };
  Eigen::VectorXd pick = snap->alpha;
  gather(pick);
  for (int again = 0; !learned_ && used > 0 && again < 3; ++again) {
    const Eigen::VectorXd next = solve_with_profile();
    if ((next - pick).norm() <= 1e-9 * (1 + next.norm())) break;
    pick = next;
    const double first_square_error = square_error;
    gather(pick);
    square_error = first_square_error;  // the predictive residual is the fit's before this profile
  }
  report.used = static_cast<int>(used);
  if (used == 0) return reject(rejections_.empty, "no usable point");
  const auto G = G_.topRows(used);
  const auto readings = m_.head(used);
  // Once learned, a profile off the fit as a whole is the sensor's fault, not the part's: its median
  // residual (a shift of the whole profile) against the fit's predictive spread for the profile's mean
  // row (plus the noise's share), with the model's own error and the learning tolerance as margins.
  const bool judged = (learned_ || in_doubt_) && used >= 10;
  double allowed = 0;
  auto off_fit = [&](const Eigen::VectorXd& alpha) {
    Eigen::VectorXd residual = readings - G * alpha;
    const auto middle = residual.begin() + used / 2;
    std::nth_element(residual.begin(), middle, residual.end());
    return std::abs(*middle) > allowed;
  };
  bool off = false;
  if (judged) {
    const Eigen::VectorXd mean_row = G.colwise().mean().transpose();
    const double spread = std::sqrt(std::max(0.0, mean_row.dot(snap->covariance * mean_row)) +
                                    1.57 * settings_.noise_sd * settings_.noise_sd / static_cast<double>(used));  // var(median) = pi/2 sigma^2 / n
    allowed = settings_.glitch_sigmas * spread + model_.error_bound() + settings_.learning_tolerance;
    off = off_fit(snap->alpha);
  }
  // This profile's share of the normal equations, kept apart while the fit is in doubt.
  auto share = [&] {
    Share s;
    s.normal.setZero(r_, r_);
    s.normal.selfadjointView<Eigen::Lower>().rankUpdate(G.transpose(), w);
    s.normal.triangularView<Eigen::StrictlyUpper>() = s.normal.transpose().eval();
    s.rhs.noalias() = w * (G.transpose() * readings);
    s.points = used;
    s.profiles = 1;
    return s;
  };
  if (learned_ && off) {
    if (++glitches_in_a_row_ >= settings_.glitch_run) {
      // So many in a row: the sensor, or the fit? In doubt, no offset until the trusted fit predicts
      // the stream again.
      learned_ = false;
      in_doubt_ = true;
      glitches_in_a_row_ = agree_trusted_ = 0;
      kept_ = Share::zero(r_);
      ++rejections_.unlearned;
      snapshot_.store(std::make_shared<const Snapshot>(Snapshot{snap->alpha, snap->covariance, false}), std::memory_order_release);
    }
    return reject(rejections_.glitch, "off the learned fit as a whole (a glitch)");
  }
  if (learned_) glitches_in_a_row_ = 0;
  if (in_doubt_) {
    // The trusted fit (as before the run) scores every profile: learning_window judged profiles in a
    // row within the allowance end the doubt; the profiles it predicted join it, the others never do.
    if (judged) agree_trusted_ = off ? 0 : agree_trusted_ + 1;
    if (off) return reject(rejections_.glitch, "off the trusted fit while it is in doubt");
    kept_ += share();
    if (agree_trusted_ < settings_.learning_window) return report;
    ++rejections_.doubts_resolved;
    normal_ += kept_.normal;
    rhs_ += kept_.rhs;
    points_ += kept_.points;
    profiles_ += kept_.profiles;
    in_doubt_ = false;
    learned_ = true;
    kept_ = Share::zero(r_);
    const Eigen::LLT<Eigen::MatrixXd> llt(normal_ + prior_precision_);
    snapshot_.store(std::make_shared<const Snapshot>(Snapshot{llt.solve(rhs_ + prior_rhs_), llt.solve(Eigen::MatrixXd::Identity(r_, r_)), true}),
                    std::memory_order_release);
    return report;
  }
  normal_.selfadjointView<Eigen::Lower>().rankUpdate(G.transpose(), w);
  normal_.triangularView<Eigen::StrictlyUpper>() = normal_.transpose().eval();
  rhs_.noalias() += w * (G.transpose() * readings);
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
  precision += prior_precision_;
  const Eigen::LLT<Eigen::MatrixXd> llt(precision);
  snapshot_.store(std::make_shared<const Snapshot>(Snapshot{llt.solve(rhs_ + prior_rhs_), llt.solve(Eigen::MatrixXd::Identity(r_, r_)), learned_}), std::memory_order_release);
  return report;
}

Estimate Predictor::estimate() const {
  // The snapshot holds the solve of the last profile (under this lock, so the counts match it).
  std::lock_guard<std::mutex> lock(ingest_);
  const auto snap = snapshot();
  Estimate e;
  e.alpha = snap->alpha;
  e.covariance = snap->covariance;
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
  if (sample_time_.size() == 1) return sample_inside_[0] != 0 ? sample_w_.row(0).dot(snap->alpha) : 0.0;
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

Eigen::RowVectorXd Predictor::offset_gradient(Eigen::Index i, const Eigen::VectorXd& alpha) const {
  if (sample_inside_[i] == 0) return Eigen::RowVectorXd::Zero(r_);
  if (model_.tool_shape != reduce::ToolShape::Ball) return sample_w_.row(i);
  const double sx = sample_s0x_[i] + sample_wx_.row(i).dot(alpha), sy = sample_s0y_[i] + sample_wy_.row(i).dot(alpha);
  const double k = model_.tool_radius / std::sqrt(1 + sx * sx + sy * sy);
  return sample_w_.row(i) + k * (sx * sample_wx_.row(i) + sy * sample_wy_.row(i));
}

double Predictor::predicted_offset_sd(double t) const {
  const auto snap = snapshot();
  if (!snap->learned || sample_time_.size() == 0) return 0;
  const auto [j, a] = reduce::locate_time(sample_time_, t);
  const Eigen::RowVectorXd g = sample_time_.size() == 1 ? offset_gradient(0, snap->alpha)
                                                        : Eigen::RowVectorXd((1 - a) * offset_gradient(j, snap->alpha) + a * offset_gradient(j + 1, snap->alpha));
  return std::sqrt(std::max(0.0, g.dot(snap->covariance * g.transpose())));
}

double Predictor::tool_offset(double t) {
  double target = predicted_offset(t);
  if (std::abs(target) > max_offset_) {
    target = std::clamp(target, -max_offset_, max_offset_);
    offsets_clamped_.fetch_add(1, std::memory_order_relaxed);
  }
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
