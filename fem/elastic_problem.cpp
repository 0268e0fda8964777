#include "fem/elastic_problem.hpp"

#include "support/byte_stream.hpp"

#include <algorithm>
#include <chrono>
#include <limits>
#include <stdexcept>

namespace drom::fem {

ElasticProblem::ElasticProblem(const Mesh& mesh, const PartShape& shape, const Material& material, std::vector<StressProfile> profiles)
    : mesh_(mesh),
      shape_(shape),
      profiles_(std::move(profiles)),
      operators_(mesh, material),
      pattern_(mesh),
      activity_(static_cast<std::size_t>(mesh.element_count()), 1.0) {
  if (profiles_.empty()) throw std::invalid_argument("ElasticProblem: at least one stress profile");
  group_sizes_ = {static_cast<Eigen::Index>(profiles_.size())};
}

Eigen::VectorXd ElasticProblem::gather(int e, const Eigen::VectorXd& u) const {
  const auto nodes = mesh_.element(e);
  Eigen::VectorXd ue(3 * static_cast<Eigen::Index>(nodes.size()));
  for (std::size_t a = 0; a < nodes.size(); ++a) ue.segment<3>(3 * static_cast<Eigen::Index>(a)) = u.segment<3>(3 * nodes[a]);
  return ue;
}

Eigen::SparseMatrix<double> ElasticProblem::assemble_stiffness(const std::vector<double>& fraction) {
  const auto t0 = std::chrono::steady_clock::now();
  Eigen::SparseMatrix<double> K = pattern_.zero_matrix();
  for (int e = 0; e < mesh_.element_count(); ++e) {
    const double a = fraction[static_cast<std::size_t>(e)];
    if (a < kMinVolumeFraction) continue;
    pattern_.add_element(K, mesh_.element(e), operators_.stiffness(e), a);
  }
  assembly_seconds_ += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return K;
}

double ElasticProblem::hold(Eigen::SparseMatrix<double>& K, const std::vector<char>& held) const {
  // Unit-scaled diagonal keeps the held block as well conditioned as the rest.
  double diag_sum = 0;
  int diag_count = 0;
  for (int c = 0; c < K.outerSize(); ++c)
    if (!held[static_cast<std::size_t>(c)]) {
      diag_sum += K.coeff(c, c);
      ++diag_count;
    }
  const double scale = diag_count ? diag_sum / diag_count : 1.0;
  for (int c = 0; c < K.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(K, c); it; ++it)
      if (held[static_cast<std::size_t>(it.row())] || held[static_cast<std::size_t>(c)]) it.valueRef() = it.row() == c ? scale : 0.0;
  return scale;
}

void ElasticProblem::equilibrate(const std::vector<int>& isostatic_dofs) {
  const auto P = static_cast<Eigen::Index>(profiles_.size());
  Eigen::MatrixXd fR = Eigen::MatrixXd::Zero(mesh_.dof_count(), P);
  for (int e = 0; e < mesh_.element_count(); ++e) {
    const Eigen::MatrixXd fe = stress_load(e);
    const auto nodes = mesh_.element(e);
    for (std::size_t a = 0; a < nodes.size(); ++a) fR.middleRows<3>(3 * nodes[a]) += fe.middleRows<3>(3 * static_cast<Eigen::Index>(a));
  }
  const std::vector<double> intact(static_cast<std::size_t>(mesh_.element_count()), 1.0);
  Eigen::SparseMatrix<double> K = assemble_stiffness(intact);
  Eigen::SparseMatrix<double> Kheld = K;
  std::vector<char> held(static_cast<std::size_t>(mesh_.dof_count()), 0);
  for (int d : isostatic_dofs) held[static_cast<std::size_t>(d)] = 1;
  hold(Kheld, held);
  Eigen::MatrixXd rhs = -fR;
  for (int d : isostatic_dofs) rhs.row(d).setZero();
  solver_.factorize(Kheld);
  u0_ = solve_by_group(rhs);
  element_loads_.clear();

  // The profile is self-equilibrated, so the 3-2-1 reactions vanish and r0 is solver noise; it is
  // kept and subtracted so the load below equals -sum_e a_e int B^T sigma0 literally.
  r0_.resize(fR.rows(), P);
  for_each_group([&](Eigen::Index first, Eigen::Index n) {
    r0_.middleCols(first, n) = fR.middleCols(first, n) + K.selfadjointView<Eigen::Lower>() * u0_.middleCols(first, n);
  });
  relative_residual_ = r0_.cwiseAbs().maxCoeff() / std::max(1e-300, fR.cwiseAbs().maxCoeff());
  equilibrated_ = true;
}

void ElasticProblem::adopt_equilibrium(const ElasticProblem& other) {
  if (&other.mesh_ != &mesh_ || other.profiles_.size() != profiles_.size() || !other.equilibrated_)
    throw std::invalid_argument("adopt_equilibrium: the other problem must be equilibrated on the same mesh and profiles");
  group_sizes_ = other.group_sizes_;
  u0_ = other.u0_;
  element_loads_.clear();
  r0_ = other.r0_;
  relative_residual_ = other.relative_residual_;
  equilibrated_ = true;
  // The same mesh has the same pattern: its ordering, if the other has one, is this one's too.
  if (!other.base_ordering_.empty()) {
    base_ordering_ = other.base_ordering_;
    full_flops_ = other.full_flops_;
  }
}

std::string ElasticProblem::equilibrium_bytes() const {
  if (!equilibrated_) throw std::logic_error("equilibrium_bytes: not equilibrated");
  ByteWriter w;
  w.put(std::vector<std::int64_t>(group_sizes_.begin(), group_sizes_.end()));
  w.put(u0_);
  w.put(r0_);
  w.put(relative_residual_);
  return w.take();
}

void ElasticProblem::adopt_equilibrium(std::string_view bytes) {
  ByteReader r(bytes, "an equilibrium");
  const auto groups = r.vector<std::int64_t>();
  Eigen::MatrixXd u0 = r.matrix(), r0 = r.matrix();
  const auto residual = r.get<double>();
  const auto P = static_cast<Eigen::Index>(profiles_.size());
  if (!r.done() || u0.rows() != mesh_.dof_count() || u0.cols() != P || r0.rows() != u0.rows() || r0.cols() != P)
    throw std::invalid_argument("adopt_equilibrium: the bytes are not an equilibrium of this mesh and these profiles");
  group_sizes_.assign(groups.begin(), groups.end());
  u0_ = std::move(u0);
  element_loads_.clear();
  r0_ = std::move(r0);
  relative_residual_ = residual;
  equilibrated_ = true;
}

void ElasticProblem::set_activity(std::vector<double> volume_fraction) {
  if (static_cast<int>(volume_fraction.size()) != mesh_.element_count())
    throw std::invalid_argument("set_activity: one volume fraction per element");
  for (double& a : volume_fraction) {
    if (!(a >= 0.0 && a <= 1.0)) throw std::invalid_argument("set_activity: volume fractions must lie in [0, 1]");
    if (a < kMinVolumeFraction) a = 0.0;
  }
  activity_ = std::move(volume_fraction);
}

void ElasticProblem::set_fixed_dofs(std::vector<int> dofs) { fixed_dofs_ = std::move(dofs); }

std::vector<char> ElasticProblem::live_nodes() const {
  std::vector<char> live(static_cast<std::size_t>(mesh_.node_count()), 0);
  for (int e = 0; e < mesh_.element_count(); ++e)
    if (activity_[static_cast<std::size_t>(e)] > 0)
      for (int n : mesh_.element(e)) live[static_cast<std::size_t>(n)] = 1;
  return live;
}

std::vector<char> ElasticProblem::held_dofs() {
  const auto live = live_nodes();
  orphan_.assign(static_cast<std::size_t>(mesh_.dof_count()), 0);
  std::vector<char> held(static_cast<std::size_t>(mesh_.dof_count()), 0);
  for (int n = 0; n < mesh_.node_count(); ++n)
    if (!live[static_cast<std::size_t>(n)])
      for (int c = 0; c < 3; ++c) orphan_[static_cast<std::size_t>(3 * n + c)] = held[static_cast<std::size_t>(3 * n + c)] = 1;
  for (int d : fixed_dofs_) held[static_cast<std::size_t>(d)] = 1;
  return held;
}

Eigen::SparseMatrix<double> ElasticProblem::held_stiffness(double* scale) {
  Eigen::SparseMatrix<double> K = assemble_stiffness(activity_);
  const double s = hold(K, held_dofs());
  if (scale) *scale = s;
  return K;
}

std::vector<std::pair<int, double>> ElasticProblem::changes_since(const std::vector<double>& then) const {
  std::vector<std::pair<int, double>> changes;
  for (int e = 0; e < mesh_.element_count(); ++e)
    if (const double delta = activity_[static_cast<std::size_t>(e)] - then[static_cast<std::size_t>(e)]; delta != 0) changes.emplace_back(e, delta);
  return changes;
}

void ElasticProblem::assemble_and_factorize() {
  K_ = held_stiffness(&anchor_scale_);
  solver_.factorize(K_);
  block_current_ = false;
}

BlockPlan ElasticProblem::plan_block(const Mesh& mesh, const RunChanges& changes) {
  if (static_cast<int>(changes.last.size()) != mesh.element_count() || changes.first.size() != changes.last.size())
    throw std::invalid_argument("plan_block: one first and one last change per element");
  // Per node: the first and the last station that change one of its elements.
  std::vector<int> node_first(static_cast<std::size_t>(mesh.node_count()), 0), node_last(node_first.size(), 0);
  int stations = 1;
  for (int e = 0; e < mesh.element_count(); ++e) {
    const auto i = static_cast<std::size_t>(e);
    const int first = changes.first[i], last = changes.last[i];
    if (last <= 0) continue;
    if (first <= 0 || first > last) throw std::invalid_argument("plan_block: an element's first change must come before its last");
    stations = std::max(stations, last + 1);
    for (int n : mesh.element(e)) {
      const auto k = static_cast<std::size_t>(n);
      node_first[k] = node_first[k] ? std::min(node_first[k], first) : first;
      node_last[k] = std::max(node_last[k], last);
    }
  }
  std::vector<int> nodes;
  for (int n = 0; n < mesh.node_count(); ++n)
    if (node_last[static_cast<std::size_t>(n)] > 0) nodes.push_back(n);
  const double m = 3.0 * static_cast<double>(nodes.size());
  // Per station j = 1 .. stations - 1, at most t_j trailing dofs, and the flops of forming T (from the
  // last one's: TrailingBlockCholesky::refactorize_trailing) and refactorizing it.
  auto flops = [&](auto trailing) {
    double total = 0, previous = m;  // at the anchor, T is formed from L_BB: as if moved back from m
    bool from_anchor = true;
    for (int j = 1; j < stations; ++j) {
      const double t = trailing(j);
      double form;
      if (from_anchor) {
        form = t * t * t / 3;
      } else if (t <= previous) {
        form = std::min(t * t * (previous - t), t * t * t / 3);
      } else {
        const double k = t - previous;
        form = k * k * k / 3 + previous * k * k + previous * previous * k;
      }
      total += form + t * t * t / 3;
      previous = t;
      from_anchor = false;
    }
    return total;
  };
  // Two orders, the cheaper kept. By last change: at station j only the dofs changed at j or later
  // trail. By first change, latest first: only those first changed at j or before. Where the tool
  // comes back over its own passes within a run, dofs are changed late, and the second wins.
  std::vector<double> count_last(static_cast<std::size_t>(stations) + 1, 0), count_first(count_last.size(), 0);
  for (int n : nodes) count_last[static_cast<std::size_t>(node_last[static_cast<std::size_t>(n)])] += 3, count_first[static_cast<std::size_t>(node_first[static_cast<std::size_t>(n)])] += 3;
  std::vector<double> at_or_after_last(count_last.size() + 1, 0), at_or_before_first(count_first.size(), 0);
  for (std::size_t j = count_last.size(); j-- > 0;) at_or_after_last[j] = at_or_after_last[j + 1] + count_last[j];
  for (std::size_t j = 1; j < count_first.size(); ++j) at_or_before_first[j] = at_or_before_first[j - 1] + count_first[j];
  const double by_last = flops([&](int j) { return at_or_after_last[static_cast<std::size_t>(j)]; });
  const double by_first = flops([&](int j) { return at_or_before_first[static_cast<std::size_t>(j)]; });
  BlockPlan plan;
  plan.stations = stations;
  plan.run_stations = std::max(stations, changes.stations);
  plan.by_first_change = by_first < by_last;
  plan.refactorization_flops = std::min(by_first, by_last);
  std::stable_sort(nodes.begin(), nodes.end(), [&](int a, int b) {
    const auto i = static_cast<std::size_t>(a), j = static_cast<std::size_t>(b);
    if (plan.by_first_change) return node_first[i] != node_first[j] ? node_first[i] > node_first[j] : node_last[i] < node_last[j];
    return node_last[i] != node_last[j] ? node_last[i] < node_last[j] : node_first[i] > node_first[j];
  });
  for (int n : nodes)
    for (int c = 0; c < 3; ++c) plan.dofs.push_back(3 * n + c);
  return plan;
}

bool ElasticProblem::block_pays(const BlockPlan& plan, double full_flops) {
  const double m = static_cast<double>(plan.dofs.size());
  return m <= 4000 && full_flops + m * m * m / 3 + plan.refactorization_flops < plan.run_stations * full_flops;
}

double ElasticProblem::full_factorization_flops() {
  // The pattern is the held stiffness's (holding changes values, never the structure), and the
  // ordering depends on the structure only.
  if (base_ordering_.empty()) base_ordering_ = fill_reducing_ordering(pattern_.zero_matrix(), &full_flops_);
  return full_flops_;
}

void ElasticProblem::assemble_and_factorize_anchor(const RunChanges& changes) {
  block_current_ = false;
  K_ = held_stiffness(&anchor_scale_);
  full_factorization_flops();
  const BlockPlan plan = plan_block(mesh_, changes);
  last_change_ = changes.last;
  if (!block_pays(plan, full_flops_)) {
    ++block_stats_.full_chunks;
    solver_.factorize(K_);
    return;
  }
  block_index_.assign(static_cast<std::size_t>(mesh_.dof_count()), -1);
  for (std::size_t b = 0; b < plan.dofs.size(); ++b) block_index_[static_cast<std::size_t>(plan.dofs[b])] = static_cast<int>(b);
  if (!block_) block_ = std::make_unique<TrailingBlockCholesky>();
  const double seconds_before = block_->anchor_seconds();
  block_current_ = block_->factorize_anchor(K_, plan.dofs, base_ordering_);
  block_stats_.anchor_seconds += block_->anchor_seconds() - seconds_before;
  if (!block_current_) {
    ++block_stats_.full_chunks;
    solver_.factorize(K_);
    return;
  }
  ++block_stats_.anchors;
  block_stats_.anchors_by_first_change += plan.by_first_change;
  block_stats_.block_dofs += static_cast<long long>(plan.dofs.size());
  block_solves_ = 0;
  // K's block rows, both triangles, for block_row_residuals.
  std::vector<Eigen::Triplet<double>> rows;
  rows.reserve(static_cast<std::size_t>(64 * plan.dofs.size()));
  for (Eigen::Index c = 0; c < K_.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(K_, c); it; ++it) {
      const auto r = it.row();
      if (const int b = block_index_[static_cast<std::size_t>(r)]; b >= 0) rows.emplace_back(b, static_cast<int>(c), it.value());
      if (const int b = block_index_[static_cast<std::size_t>(c)]; b >= 0 && r != c) rows.emplace_back(b, static_cast<int>(r), it.value());
    }
  block_rows_.resize(static_cast<Eigen::Index>(plan.dofs.size()), K_.cols());
  block_rows_.setFromTriplets(rows.begin(), rows.end());
  anchor_activity_ = factor_activity_ = activity_;
  anchor_held_ = factor_held_ = held_dofs();
}

void ElasticProblem::refactorize_changed() {
  if (!block_current_) {
    assemble_and_factorize();
    return;
  }
  // S changes by sum over the elements changed since the last factorization of (a - a_then) K_e,
  // on their dofs, and on the rows and columns of dofs newly held (orphans appear as material
  // goes), which the full assembly holds as it does: all from the first block dof they touch on.
  const auto changes = changes_since(factor_activity_);
  const auto held = held_dofs();
  const auto m = block_->block_size();
  Eigen::Index first = m;
  for (const auto& [e, delta] : changes) {
    if (last_change_[static_cast<std::size_t>(e)] == 0)
      throw std::logic_error("refactorize_changed: element " + std::to_string(e) + " changed outside the anchor's block");
    for (int n : mesh_.element(e)) first = std::min<Eigen::Index>(first, block_index_[static_cast<std::size_t>(3 * n)]);
  }
  for (int d : block_->block())
    if (held[static_cast<std::size_t>(d)] != factor_held_[static_cast<std::size_t>(d)]) first = std::min<Eigen::Index>(first, block_index_[static_cast<std::size_t>(d)]);
  if (first == m) {
    ++block_stats_.unchanged_stations;
    return;
  }
  // A node's three dofs are consecutive in the block, x first.
  auto change = [&](Eigen::Ref<Eigen::MatrixXd> T) {
    for (const auto& [e, delta] : changes) {
      const auto nodes = mesh_.element(e);
      const Eigen::MatrixXd& Ke = operators_.stiffness(e);
      for (std::size_t a = 0; a < 3 * nodes.size(); ++a) {
        const Eigen::Index i = block_index_[static_cast<std::size_t>(3 * nodes[a / 3] + static_cast<int>(a % 3))] - first;
        for (std::size_t b = 0; b < 3 * nodes.size(); ++b) {
          const Eigen::Index j = block_index_[static_cast<std::size_t>(3 * nodes[b / 3] + static_cast<int>(b % 3))] - first;
          T(i, j) += delta * Ke(static_cast<Eigen::Index>(a), static_cast<Eigen::Index>(b));
        }
      }
    }
    for (Eigen::Index i = 0; i < T.rows(); ++i) {
      if (!held[static_cast<std::size_t>(block_->block()[static_cast<std::size_t>(first + i)])]) continue;
      T.row(i).setZero();
      T.col(i).setZero();
      T(i, i) = anchor_scale_;
    }
  };
  const long long trailing_before = block_->trailing_dofs();
  const double seconds_before = block_->refactorize_seconds();
  const bool positive = block_->refactorize_trailing(first, change);
  block_stats_.refactorize_seconds += block_->refactorize_seconds() - seconds_before;
  if (!positive) {
    // Round-off cannot make S indefinite where the full matrix is not: leave it to the full
    // factorization to say which it is.
    assemble_and_factorize();
    return;
  }
  factor_activity_ = activity_;
  factor_held_ = held;
  ++block_stats_.block_refactorizations;
  block_stats_.trailing_dofs += block_->trailing_dofs() - trailing_before;
}

const Eigen::MatrixXd& ElasticProblem::element_load(int e) {
  if (element_loads_.empty()) element_loads_.resize(static_cast<std::size_t>(mesh_.element_count()));
  Eigen::MatrixXd& fe = element_loads_[static_cast<std::size_t>(e)];
  if (fe.size() > 0) return fe;
  fe = stress_load(e);
  const Eigen::MatrixXd& Ke = operators_.stiffness(e);
  for (Eigen::Index p = 0; p < fe.cols(); ++p) fe.col(p) += Ke * gather(e, u0_.col(p));
  return fe;
}

Eigen::MatrixXd ElasticProblem::solve() {
  if (!equilibrated_) throw std::logic_error("ElasticProblem::solve before equilibrate");
  // -sum_e a_e (f_R,e + K_e u0_e) = -r0 + sum_e (1 - a_e)(f_R,e + K_e u0_e): only removed material
  // contributes, which is cheap (few elements per station) and free of cancellation.
  Eigen::MatrixXd F = -r0_;
  for (int e = 0; e < mesh_.element_count(); ++e) {
    const double removed = 1.0 - activity_[static_cast<std::size_t>(e)];
    if (removed <= 0) continue;
    const Eigen::MatrixXd& fe = element_load(e);
    const auto nodes = mesh_.element(e);
    for (std::size_t a = 0; a < nodes.size(); ++a) F.middleRows<3>(3 * nodes[a]) += removed * fe.middleRows<3>(3 * static_cast<Eigen::Index>(a));
  }
  zero_held_rows(F);
  Eigen::MatrixXd U = solve_by_group(F);
  if (block_current_) {
    // Held exactly, as the full path holds them: the block path leaves round-off on orphans whose
    // coupling it cancelled rather than removed.
    zero_held_rows(U);
  }
  if (!block_current_) {
    if (measure_full_residual_) {
      const auto t0 = std::chrono::steady_clock::now();
      block_stats_.worst_full_residual = std::max(block_stats_.worst_full_residual, column_residuals(F, U).maxCoeff());
      block_stats_.residual_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    }
    return U;
  }
  // Each group on its own, so that a group's columns stay what a problem holding it alone gives.
  const auto t0 = std::chrono::steady_clock::now();
  const bool whole = block_solves_++ % kWholeResidualEvery == 0;
  const Eigen::VectorXd residuals = whole ? column_residuals(F, U) : block_row_residuals(F, U);
  block_stats_.whole_residuals += whole;
  block_stats_.residual_seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  bool factorized = false;
  for_each_group([&](Eigen::Index first, Eigen::Index n) {
    const double residual = residuals.segment(first, n).maxCoeff();
    if (residual <= residual_bound_) {
      block_stats_.worst_residual = std::max(block_stats_.worst_residual, residual);
      return;
    }
    ++block_stats_.residual_fallbacks;
    if (!factorized) {
      // The full path's matrix, bit for bit; K_ stays the anchor's for the chunk's next stations,
      // and S starts again from the anchor's, in case its updates gathered the error.
      solver_.factorize(held_stiffness());
      factorized = true;
      block_->reset_to_anchor();
      factor_activity_ = anchor_activity_;
      factor_held_ = anchor_held_;
    }
    U.middleCols(first, n) = solver_.solve(F.middleCols(first, n));
  });
  return U;
}

namespace {

// ||r_p|| / ||f_p|| per column.
Eigen::VectorXd relative_norms(const Eigen::MatrixXd& R, const Eigen::MatrixXd& F) {
  Eigen::VectorXd ratios(F.cols());
  for (Eigen::Index p = 0; p < F.cols(); ++p) {
    const double f = F.col(p).norm(), r = R.col(p).norm();
    ratios(p) = f > 0 ? r / f : (r > 0 ? std::numeric_limits<double>::infinity() : 0.0);
  }
  return ratios;
}

}  // namespace

template <class RowOf>
void ElasticProblem::subtract_changed_elements(const Eigen::MatrixXd& U, RowOf row_of, Eigen::MatrixXd& R) {
  for (const auto& [e, delta] : changes_since(anchor_activity_)) {
    const auto nodes = mesh_.element(e);
    Eigen::MatrixXd ue(3 * static_cast<Eigen::Index>(nodes.size()), U.cols());
    for (std::size_t a = 0; a < nodes.size(); ++a) ue.middleRows<3>(3 * static_cast<Eigen::Index>(a)) = U.middleRows<3>(3 * nodes[a]);
    const Eigen::MatrixXd fe = delta * (operators_.stiffness(e) * ue);
    for (std::size_t a = 0; a < nodes.size(); ++a) R.middleRows<3>(row_of(nodes[a])) -= fe.middleRows<3>(3 * static_cast<Eigen::Index>(a));
  }
}

Eigen::VectorXd ElasticProblem::block_row_residuals(const Eigen::MatrixXd& F, const Eigen::MatrixXd& U) {
  const auto& block = block_->block();
  Eigen::MatrixXd R(static_cast<Eigen::Index>(block.size()), F.cols());
  for (std::size_t b = 0; b < block.size(); ++b) R.row(static_cast<Eigen::Index>(b)) = F.row(block[b]);
  R.noalias() -= block_rows_ * U;
  subtract_changed_elements(U, [&](int node) { return block_index_[static_cast<std::size_t>(3 * node)]; }, R);
  // Held now: held at the anchor (fixed dofs and the orphans then), or orphaned since.
  for (std::size_t b = 0; b < block.size(); ++b) {
    const auto d = static_cast<std::size_t>(block[b]);
    if (orphan_[d] || anchor_held_[d]) R.row(static_cast<Eigen::Index>(b)).setZero();
  }
  return relative_norms(R, F);
}

void ElasticProblem::zero_held_rows(Eigen::MatrixXd& M) const {
  for (int d = 0; d < mesh_.dof_count(); ++d)
    if (orphan_[static_cast<std::size_t>(d)]) M.row(d).setZero();
  for (int d : fixed_dofs_) M.row(d).setZero();
}

Eigen::VectorXd ElasticProblem::column_residuals(const Eigen::MatrixXd& F, const Eigen::MatrixXd& U) {
  // After a block refactorization K is the anchor's K_ plus the changed elements' (a - a_anchor) K_e;
  // held rows are F's zeros.
  Eigen::MatrixXd R = F;
  R.noalias() -= K_.selfadjointView<Eigen::Lower>() * U;
  if (block_current_) subtract_changed_elements(U, [](int node) { return 3 * node; }, R);
  zero_held_rows(R);
  return relative_norms(R, F);
}

void ElasticProblem::set_profile_groups(std::vector<int> sizes) {
  if (equilibrated_) throw std::logic_error("set_profile_groups after equilibrate");
  std::size_t total = 0;
  for (int n : sizes) {
    if (n < 1) throw std::invalid_argument("set_profile_groups: every group needs a profile");
    total += static_cast<std::size_t>(n);
  }
  if (total != profiles_.size()) throw std::invalid_argument("set_profile_groups: the group sizes must add up to the profile count");
  group_sizes_.assign(sizes.begin(), sizes.end());
}

Eigen::MatrixXd ElasticProblem::stress_load(int e) const {
  Eigen::MatrixXd f(3 * static_cast<Eigen::Index>(mesh_.element(e).size()), static_cast<Eigen::Index>(profiles_.size()));
  const std::span<const StressProfile> all(profiles_);
  for_each_group([&](Eigen::Index first, Eigen::Index n) {
    f.middleCols(first, n) = operators_.stress_load(e, all.subspan(static_cast<std::size_t>(first), static_cast<std::size_t>(n)), shape_);
  });
  return f;
}

Eigen::MatrixXd ElasticProblem::solve_by_group(const Eigen::MatrixXd& rhs) {
  auto solve = [&](const Eigen::MatrixXd& b) -> Eigen::MatrixXd {
    if (!block_current_) return solver_.solve(b);
    const double seconds_before = block_->solve_seconds();
    Eigen::MatrixXd x = block_->solve(b);
    block_stats_.solve_seconds += block_->solve_seconds() - seconds_before;
    return x;
  };
  if (group_sizes_.size() == 1) return solve(rhs);  // no copy of the right-hand sides
  Eigen::MatrixXd u(rhs.rows(), rhs.cols());
  for_each_group([&](Eigen::Index first, Eigen::Index n) { u.middleCols(first, n) = solve(rhs.middleCols(first, n)); });
  return u;
}

std::vector<Vector6d> ElasticProblem::element_stresses(int p, const Eigen::VectorXd& u) const {
  const Eigen::VectorXd total = u0_.col(p) + u;
  std::vector<Vector6d> stresses(static_cast<std::size_t>(mesh_.element_count()));
  for (int e = 0; e < mesh_.element_count(); ++e)
    stresses[static_cast<std::size_t>(e)] = operators_.mean_stress(e, gather(e, total), &profiles_[static_cast<std::size_t>(p)], shape_);
  return stresses;
}

Vector6d ElasticProblem::initial_stress(int p, int e, const Eigen::Vector3d& xi) const {
  if (!equilibrated_) throw std::logic_error("initial_stress before equilibrate");
  return operators_.point_stress(e, xi, gather(e, u0_.col(p)), &profiles_[static_cast<std::size_t>(p)], shape_);
}

}  // namespace drom::fem
