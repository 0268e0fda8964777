// Issue 28: refactorizing only the block of dofs a station changes (fem/trailing_block_cholesky.hpp)
// must solve the changed matrix as a full factorization does, and the FE problem's block path must
// give the full path's displacements, falling back to it when its residual check fails.
#include "fem/elastic_problem.hpp"
#include "fem/node_sets.hpp"
#include "fem/structured_mesh.hpp"
#include "fem/supports.hpp"
#include "fem/trailing_block_cholesky.hpp"

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <random>
#include <vector>

using namespace drom;

namespace {

// A 3D 7-point Laplacian on an nx x ny x nz grid with a spring to ground at every node: SPD. Edges
// inside `soft` (both ends) are scaled by `softness`, as removed material scales its stiffness.
struct Grid {
  int nx, ny, nz;
  int index(int i, int j, int k) const { return i + nx * (j + ny * k); }
  int size() const { return nx * ny * nz; }
};

Eigen::SparseMatrix<double> laplacian(const Grid& g, const std::vector<char>& soft, double softness) {
  std::vector<Eigen::Triplet<double>> t;
  auto edge = [&](int a, int b) {
    const double w = soft[static_cast<std::size_t>(a)] && soft[static_cast<std::size_t>(b)] ? softness : 1.0;
    t.emplace_back(a, a, w);
    t.emplace_back(b, b, w);
    t.emplace_back(std::max(a, b), std::min(a, b), -w);
  };
  for (int k = 0; k < g.nz; ++k)
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i) {
        const int a = g.index(i, j, k);
        t.emplace_back(a, a, 1e-3);
        if (i + 1 < g.nx) edge(a, g.index(i + 1, j, k));
        if (j + 1 < g.ny) edge(a, g.index(i, j + 1, k));
        if (k + 1 < g.nz) edge(a, g.index(i, j, k + 1));
      }
  Eigen::SparseMatrix<double> A(g.size(), g.size());
  A.setFromTriplets(t.begin(), t.end());
  return A;
}

// B x B of A (full symmetric, block order).
Eigen::MatrixXd block_of(const Eigen::SparseMatrix<double>& lower, const std::vector<int>& block) {
  const Eigen::MatrixXd full = Eigen::MatrixXd(Eigen::SparseMatrix<double>(lower.selfadjointView<Eigen::Lower>()));
  Eigen::MatrixXd b(static_cast<Eigen::Index>(block.size()), static_cast<Eigen::Index>(block.size()));
  for (std::size_t i = 0; i < block.size(); ++i)
    for (std::size_t j = 0; j < block.size(); ++j) b(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = full(block[i], block[j]);
  return b;
}

double relative_difference(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) { return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff(); }

}  // namespace

TEST(TrailingBlockCholesky, RefactorizingTheBlockSolvesTheChangedMatrix) {
  const Grid g{12, 10, 6};
  std::vector<char> in_block(static_cast<std::size_t>(g.size()), 0);
  std::vector<int> block;
  for (int k = 3; k < 6; ++k)
    for (int j = 2; j < 6; ++j)
      for (int i = 4; i < 9; ++i) in_block[static_cast<std::size_t>(g.index(i, j, k))] = 1;
  // Unsorted on purpose: the block keeps the caller's order.
  for (int d = g.size() - 1; d >= 0; --d)
    if (in_block[static_cast<std::size_t>(d)]) block.push_back(d);
  const Eigen::SparseMatrix<double> anchor = laplacian(g, in_block, 1.0);
  fem::TrailingBlockCholesky solver;
  ASSERT_TRUE(solver.factorize_anchor(anchor, block, fem::fill_reducing_ordering(anchor)));
  EXPECT_EQ(solver.block_size(), 60);

  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::MatrixXd rhs(g.size(), 3);
  for (Eigen::Index i = 0; i < rhs.size(); ++i) rhs.data()[i] = u(rng);
  // The anchor itself, then the block's stiffness lowered step by step, as material goes: each
  // change is measured from the last matrix.
  Eigen::SparseMatrix<double> previous = anchor;
  for (double softness : {1.0, 0.6, 0.2, 1e-3}) {
    const Eigen::SparseMatrix<double> changed = laplacian(g, in_block, softness);
    const Eigen::MatrixXd change = block_of(changed, block) - block_of(previous, block);
    ASSERT_TRUE(solver.refactorize_trailing(0, [&](Eigen::Ref<Eigen::MatrixXd> T) { T += change; }));
    previous = changed;
    const Eigen::MatrixXd x = solver.solve(rhs);
    const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> reference(changed);
    EXPECT_LT(relative_difference(x, reference.solve(rhs)), 1e-11) << softness;
    EXPECT_LT((changed.selfadjointView<Eigen::Lower>() * x - rhs).norm(), 1e-12 * rhs.norm()) << softness;
  }
  // Outside the block the right-hand side did not change: one forward solve served all four.
  EXPECT_EQ(solver.forward_solves(), 1);
  rhs(0, 0) += 1;
  const Eigen::MatrixXd x = solver.solve(rhs);
  EXPECT_EQ(solver.forward_solves(), 2);
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> reference(laplacian(g, in_block, 1e-3));
  EXPECT_LT(relative_difference(x, reference.solve(rhs)), 1e-11);
}

TEST(TrailingBlockCholesky, RefactorizingOnlyTheTrailingPartSolvesTheChangedMatrix) {
  // Changes confined to the block's indices from some `first` on, which moves on and back: each
  // station refactorizes only from there, forming its T from the last one's.
  const Grid g{10, 8, 5};
  std::vector<char> in_block(static_cast<std::size_t>(g.size()), 0);
  std::vector<int> block;
  for (int k = 2; k < 5; ++k)
    for (int j = 1; j < 7; ++j)
      for (int i = 2; i < 8; ++i) in_block[static_cast<std::size_t>(g.index(i, j, k))] = 1, block.push_back(g.index(i, j, k));
  const auto m = static_cast<Eigen::Index>(block.size());
  const Eigen::SparseMatrix<double> anchor = laplacian(g, in_block, 1.0);
  fem::TrailingBlockCholesky solver;
  ASSERT_TRUE(solver.factorize_anchor(anchor, block, fem::fill_reducing_ordering(anchor)));
  Eigen::MatrixXd current = Eigen::MatrixXd(Eigen::SparseMatrix<double>(anchor.selfadjointView<Eigen::Lower>()));
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> u(-1, 1);
  Eigen::MatrixXd rhs(g.size(), 2);
  for (Eigen::Index i = 0; i < rhs.size(); ++i) rhs.data()[i] = u(rng);
  long long refactorized = 0;
  for (const Eigen::Index first : {m / 2, 2 * m / 3, m / 5, m - 3, Eigen::Index{0}, m / 2 + 1, m / 2 + 2, m / 3}) {
    // A symmetric change on the trailing dofs that keeps the matrix positive definite.
    Eigen::MatrixXd change = Eigen::MatrixXd::Zero(m - first, m - first);
    for (Eigen::Index i = 0; i < change.rows(); ++i) {
      change(i, i) = 0.5 + 0.5 * u(rng);
      for (Eigen::Index j = 0; j < i; ++j) change(i, j) = change(j, i) = 0.01 * u(rng);
    }
    for (Eigen::Index i = first; i < m; ++i)
      for (Eigen::Index j = first; j < m; ++j) current(block[static_cast<std::size_t>(i)], block[static_cast<std::size_t>(j)]) += change(i - first, j - first);
    ASSERT_TRUE(solver.refactorize_trailing(first, [&](Eigen::Ref<Eigen::MatrixXd> T) { T += change; })) << first;
    refactorized += m - first;
    const Eigen::MatrixXd x = solver.solve(rhs);
    EXPECT_LT(relative_difference(x, current.llt().solve(rhs)), 1e-11) << first;
    EXPECT_LT((current * x - rhs).norm(), 1e-12 * rhs.norm()) << first;
  }
  EXPECT_EQ(solver.trailing_dofs(), refactorized);
  // Back to the anchor: the next change is measured from it.
  solver.reset_to_anchor();
  const Eigen::MatrixXd reference = Eigen::MatrixXd(Eigen::SparseMatrix<double>(anchor.selfadjointView<Eigen::Lower>()));
  EXPECT_LT(relative_difference(solver.solve(rhs), reference.llt().solve(rhs)), 1e-11);
  EXPECT_THROW(solver.refactorize_trailing(m + 1, [](Eigen::Ref<Eigen::MatrixXd>) {}), std::invalid_argument);
}

TEST(TrailingBlockCholesky, RefusesAnIndefiniteBlockAndKeepsThePreviousOne) {
  const Grid g{6, 6, 4};
  std::vector<char> in_block(static_cast<std::size_t>(g.size()), 0);
  std::vector<int> block;
  for (int d = 0; d < 10; ++d) in_block[static_cast<std::size_t>(d)] = 1, block.push_back(d);
  const Eigen::SparseMatrix<double> A = laplacian(g, in_block, 1.0);
  fem::TrailingBlockCholesky solver;
  ASSERT_TRUE(solver.factorize_anchor(A, block, fem::fill_reducing_ordering(A)));
  EXPECT_FALSE(solver.refactorize_trailing(2, [](Eigen::Ref<Eigen::MatrixXd> T) { T(1, 1) = -1; }));
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(g.size(), -1, 2);
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> reference(A);
  EXPECT_LT(relative_difference(solver.solve(b), reference.solve(b)), 1e-11);
}

TEST(TrailingBlockCholesky, RefusesBadBlocksAndSolvesOnlyAfterAnAnchor) {
  const Grid g{5, 5, 5};
  const std::vector<char> none(static_cast<std::size_t>(g.size()), 0);
  const Eigen::SparseMatrix<double> A = laplacian(g, none, 1.0);
  fem::TrailingBlockCholesky solver;
  EXPECT_THROW(solver.solve(Eigen::VectorXd::Ones(g.size())), std::logic_error);
  EXPECT_THROW(solver.factorize_anchor(A, std::vector<int>{1, 1}, fem::fill_reducing_ordering(A)), std::invalid_argument);
  EXPECT_THROW(solver.factorize_anchor(A, std::vector<int>{g.size()}, fem::fill_reducing_ordering(A)), std::invalid_argument);
  EXPECT_THROW(solver.factorize_anchor(A, std::vector<int>{1}, std::vector<int>{0, 1}), std::invalid_argument);
  // An empty block is a plain factorization in the given order.
  ASSERT_TRUE(solver.factorize_anchor(A, std::vector<int>{}, fem::fill_reducing_ordering(A)));
  const Eigen::VectorXd b = Eigen::VectorXd::LinSpaced(g.size(), -1, 2);
  const Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>, Eigen::Lower> reference(A);
  EXPECT_LT(relative_difference(solver.solve(b), reference.solve(b)), 1e-12);
}

namespace {

// A 6 x 6 x 3 Hex20 plate held at its four bottom corners, with the top layer's middle 2 x 2 elements
// machined away in steps (their shared top nodes end as orphans), one station after another.
struct MachinedPlate {
  geometry::PartShape shape = geometry::PartShape::plate(60, 60, 6);
  fem::Mesh mesh = fem::make_structured_hex_mesh(shape, {6, 6, 3, 1.0});
  std::vector<fem::StressProfile> profiles = fem::unit_profiles(fem::legendre_degrees(fem::ProfileParity::Even, 4));
  std::vector<int> clamped;
  std::vector<char> pocket;  // the machined elements
  std::vector<std::vector<double>> stations;

  MachinedPlate() {
    const auto faces = fem::boundary_faces(mesh);
    clamped = fem::node_dofs(fem::face_nodes_where(mesh, faces, [](const Eigen::Vector3d& c) {
      return c.z() < 1e-9 && (c.x() < 10 || c.x() > 50) && (c.y() < 10 || c.y() > 50);  // the corner elements' bottom faces
    }));
    pocket.assign(static_cast<std::size_t>(mesh.element_count()), 0);
    for (int e = 0; e < mesh.element_count(); ++e) {
      const Eigen::Vector3d c = mesh.centroid(e);
      pocket[static_cast<std::size_t>(e)] = c.z() > 4 && std::abs(c.x() - 30) < 10 && std::abs(c.y() - 30) < 10;
    }
    for (double a : {1.0, 0.7, 0.3, 0.0}) {
      std::vector<double> activity(static_cast<std::size_t>(mesh.element_count()), 1.0);
      for (std::size_t e = 0; e < activity.size(); ++e)
        if (pocket[e]) activity[e] = a;
      stations.push_back(activity);
    }
  }
  // The full path equilibrated on the intact plate, and the block path adopting that equilibrium.
  void equilibrate(fem::ElasticProblem& full, fem::ElasticProblem& block) const {
    full.equilibrate(fem::isostatic_dofs(mesh, shape, std::vector<char>(static_cast<std::size_t>(mesh.node_count()), 1)));
    block.adopt_equilibrium(full);
  }
  fem::ElasticProblem problem() const {
    fem::ElasticProblem p(mesh, shape, {71700, 0.33}, profiles);
    p.set_fixed_dofs(clamped);
    return p;
  }
};

// The flagged elements change at every later station of a run of `stations`.
fem::RunChanges changing_throughout(const std::vector<char>& flagged, int stations) {
  fem::RunChanges run{std::vector<int>(flagged.size(), 0), std::vector<int>(flagged.size(), 0), stations};
  for (std::size_t e = 0; e < flagged.size(); ++e)
    if (flagged[e]) run.first[e] = 1, run.last[e] = stations - 1;
  return run;
}

// Station k of a run: the first factorizes with the changing elements' dofs last, the others
// refactorize that block.
void factorize_station(fem::ElasticProblem& block, const std::vector<double>& activity, std::size_t k, const fem::RunChanges& changes) {
  block.set_activity(activity);
  if (k == 0)
    block.assemble_and_factorize_anchor(changes);
  else
    block.refactorize_changed();
}

}  // namespace

TEST(BlockRefactorization, GivesTheFullFactorizationsDisplacementsAsMaterialGoes) {
  const MachinedPlate plate;
  fem::ElasticProblem full = plate.problem(), block = plate.problem();
  plate.equilibrate(full, block);
  full.measure_full_residuals(true);
  for (std::size_t k = 0; k < plate.stations.size(); ++k) {
    full.set_activity(plate.stations[k]);
    full.assemble_and_factorize();
    factorize_station(block, plate.stations[k], k, changing_throughout(plate.pocket, 4));
    const Eigen::MatrixXd U = full.solve(), X = block.solve();
    EXPECT_LT(relative_difference(X, U), 1e-10) << "station " << k;
  }
  // The last station's pocket is gone: the top nodes only pocket elements held are orphans, at zero.
  EXPECT_GT(std::count(block.orphan_dofs().begin(), block.orphan_dofs().end(), 1), 0);
  const auto& stats = block.block_stats();
  EXPECT_EQ(stats.anchors, 1);
  EXPECT_EQ(stats.block_refactorizations, 3);
  EXPECT_EQ(stats.residual_fallbacks, 0);
  // As small as the full factorization's own residual (its round-off), within a factor of 10.
  EXPECT_GT(stats.worst_residual, 0);
  EXPECT_LT(stats.worst_residual, 10 * full.block_stats().worst_full_residual);
  EXPECT_EQ(block.solver_stats().factorizations, 0);  // never a full one

  // A change outside the block is a caller's error.
  std::vector<double> elsewhere = plate.stations.back();
  elsewhere[0] = 0.5;
  block.set_activity(elsewhere);
  EXPECT_THROW(block.refactorize_changed(), std::logic_error);
}

TEST(BlockRefactorization, AFailedResidualCheckSolvesAgainOnAFullFactorization) {
  // A bound no solve meets forces the fallback at every station: the answers are then the full
  // path's, bit for bit.
  const MachinedPlate plate;
  fem::ElasticProblem full = plate.problem(), block = plate.problem();
  plate.equilibrate(full, block);
  block.set_residual_bound(1e-300);
  for (std::size_t k = 0; k < plate.stations.size(); ++k) {
    full.set_activity(plate.stations[k]);
    full.assemble_and_factorize();
    factorize_station(block, plate.stations[k], k, changing_throughout(plate.pocket, 4));
    EXPECT_TRUE(block.solve() == full.solve()) << "station " << k;
  }
  // Every station's block solve failed the check and was solved again in full; the next station still
  // refactorized its block first.
  EXPECT_EQ(block.block_stats().residual_fallbacks, 4);
  EXPECT_EQ(block.block_stats().block_refactorizations, 3);
  EXPECT_EQ(block.solver_stats().factorizations, 4);
}

TEST(BlockRefactorization, AfterAFailedResidualCheckTheNextStationsRebuildTheirBlockAndPass) {
  // Station 1's check fails (a bound no solve meets); stations 2 and 3, checked again at the usual
  // bound, start S from the anchor's again and keep their block solves.
  const MachinedPlate plate;
  fem::ElasticProblem full = plate.problem(), block = plate.problem();
  plate.equilibrate(full, block);
  for (std::size_t k = 0; k < plate.stations.size(); ++k) {
    full.set_activity(plate.stations[k]);
    full.assemble_and_factorize();
    block.set_residual_bound(k == 1 ? 1e-300 : 1e-8);
    factorize_station(block, plate.stations[k], k, changing_throughout(plate.pocket, 4));
    const Eigen::MatrixXd U = full.solve(), X = block.solve();
    if (k == 1) {
      EXPECT_TRUE(X == U);
    } else {
      EXPECT_LT(relative_difference(X, U), 1e-10) << "station " << k;
    }
  }
  const auto& stats = block.block_stats();
  EXPECT_EQ(stats.residual_fallbacks, 1);
  EXPECT_EQ(stats.block_refactorizations, 3);
  EXPECT_EQ(block.solver_stats().factorizations, 1);  // station 1's fallback only
  // Station 2 refactorized from the anchor's S: the whole block again (every pocket dof changed by then).
  EXPECT_GE(stats.trailing_dofs, 2 * stats.block_dofs);
}

TEST(BlockRefactorization, ARunThatChangesNothingFactorizesOnce) {
  const MachinedPlate plate;
  fem::ElasticProblem full = plate.problem(), block = plate.problem();
  plate.equilibrate(full, block);
  const std::vector<char> nothing(static_cast<std::size_t>(plate.mesh.element_count()), 0);
  full.set_activity(plate.stations[2]);
  full.assemble_and_factorize();
  const Eigen::MatrixXd U = full.solve();
  for (std::size_t k = 0; k < 3; ++k) {
    factorize_station(block, plate.stations[2], k, changing_throughout(nothing, 3));
    EXPECT_LT(relative_difference(block.solve(), U), 1e-10) << "station " << k;
  }
  EXPECT_EQ(block.block_stats().anchors, 1);
  EXPECT_EQ(block.block_stats().block_dofs, 0);
  EXPECT_EQ(block.block_stats().unchanged_stations, 2);
  EXPECT_EQ(block.solver_stats().factorizations, 0);
}

TEST(BlockRefactorization, ABlockTooLargeToPayFactorizesInFull) {
  // Every element flagged as changing: the block is the whole mesh, whose dense refactorization
  // would cost far more than a full one. The run factorizes in full, bit for bit the full path.
  const MachinedPlate plate;
  fem::ElasticProblem full = plate.problem(), block = plate.problem();
  plate.equilibrate(full, block);
  const std::vector<char> everything(static_cast<std::size_t>(plate.mesh.element_count()), 1);
  for (std::size_t k = 0; k < plate.stations.size(); ++k) {
    full.set_activity(plate.stations[k]);
    full.assemble_and_factorize();
    factorize_station(block, plate.stations[k], k, changing_throughout(everything, 4));
    EXPECT_TRUE(block.solve() == full.solve()) << "station " << k;
  }
  EXPECT_EQ(block.block_stats().full_chunks, 1);
  EXPECT_EQ(block.block_stats().anchors, 0);
  EXPECT_EQ(block.block_stats().block_refactorizations, 0);
  EXPECT_EQ(block.solver_stats().factorizations, 4);
}

TEST(BlockRefactorization, StationsRefactorizeFromTheFirstDofTheyChangeAndMayChangeNothing) {
  // The pocket's four elements machined one after another, one station with no change between:
  // ordered by their last change, a station's changes start part-way into the block.
  const MachinedPlate plate;
  std::vector<int> pocket;
  for (int e = 0; e < plate.mesh.element_count(); ++e)
    if (plate.pocket[static_cast<std::size_t>(e)]) pocket.push_back(e);
  ASSERT_EQ(pocket.size(), 4u);
  // Per station, each pocket element's fraction.
  const std::vector<std::array<double, 4>> fractions = {{1, 1, 1, 1}, {0.5, 1, 1, 1}, {0, 1, 1, 1}, {0, 0.3, 1, 1}, {0, 0, 0.6, 1},
                                                        {0, 0, 0.6, 1}, {0, 0, 0, 0.2}, {0, 0, 0, 0}};
  std::vector<std::vector<double>> history;
  for (const auto& f : fractions) {
    std::vector<double> activity(static_cast<std::size_t>(plate.mesh.element_count()), 1.0);
    for (std::size_t i = 0; i < 4; ++i) activity[static_cast<std::size_t>(pocket[i])] = f[i];
    history.push_back(activity);
  }
  fem::RunChanges run{std::vector<int>(static_cast<std::size_t>(plate.mesh.element_count()), 0),
                      std::vector<int>(static_cast<std::size_t>(plate.mesh.element_count()), 0)};
  for (std::size_t k = 1; k < history.size(); ++k)
    for (std::size_t e = 0; e < run.first.size(); ++e)
      if (history[k][e] != history[k - 1][e]) {
        if (run.first[e] == 0) run.first[e] = static_cast<int>(k);
        run.last[e] = static_cast<int>(k);
      }
  const auto plan = fem::ElasticProblem::plan_block(plate.mesh, run);
  EXPECT_EQ(plan.stations, 8);

  fem::ElasticProblem full = plate.problem(), block = plate.problem();
  plate.equilibrate(full, block);
  for (std::size_t k = 0; k < history.size(); ++k) {
    full.set_activity(history[k]);
    full.assemble_and_factorize();
    factorize_station(block, history[k], k, run);
    EXPECT_LT(relative_difference(block.solve(), full.solve()), 1e-10) << "station " << k;
  }
  const auto& stats = block.block_stats();
  EXPECT_EQ(stats.anchors, 1);
  EXPECT_EQ(stats.block_refactorizations, 6);
  EXPECT_EQ(stats.unchanged_stations, 1);
  EXPECT_EQ(stats.block_dofs, static_cast<long long>(plan.dofs.size()));
  // Later stations refactorized less than the whole block.
  EXPECT_LT(stats.trailing_dofs, 6 * stats.block_dofs);
  EXPECT_EQ(stats.residual_fallbacks, 0);
  // Block solves checked on every row: the anchor's and every kWholeResidualEvery-th after it.
  EXPECT_EQ(stats.whole_residuals, 2);
}

namespace {

// What BlockPlan's estimate should be for trailing sizes t_1 .. t_{J-1} (recomputed here from the
// trailing sizes, not from the plan): forming T (from L_BB at station 1, then from the last T,
// moved on or back) and refactorizing it.
double plan_flops(const std::vector<double>& t, double m) {
  auto cube = [](double x) { return x * x * x / 3; };
  double total = 0, previous = m;
  for (std::size_t j = 0; j < t.size(); ++j) {
    double form;
    if (j == 0) form = cube(t[j]);
    else if (t[j] <= previous) form = std::min(t[j] * t[j] * (previous - t[j]), cube(t[j]));
    else form = cube(t[j] - previous) + previous * (t[j] - previous) * (t[j] - previous) + previous * previous * (t[j] - previous);
    total += form + cube(t[j]);
    previous = t[j];
  }
  return total;
}

}  // namespace

TEST(BlockPlan, OrdersTheBlockByTheCheaperOfLastAndFirstChange) {
  // Three elements in a row, a, b and c.
  const auto shape = geometry::PartShape::plate(30, 10, 10);
  const auto mesh = fem::make_structured_hex_mesh(shape, {3, 1, 1, 1.0});
  ASSERT_EQ(mesh.element_count(), 3);
  auto element_at = [&](double x) {
    for (int e = 0; e < 3; ++e)
      if (std::abs(mesh.centroid(e).x() - x) < 1) return static_cast<std::size_t>(e);
    return std::size_t{99};
  };
  const std::size_t a = element_at(5), b = element_at(15), c = element_at(25);
  // Per node, the first and last change of its elements; the trailing sizes of both orders.
  auto check = [&](const fem::RunChanges& run, bool by_first_expected) {
    const auto plan = fem::ElasticProblem::plan_block(mesh, run);
    std::vector<int> first(static_cast<std::size_t>(mesh.node_count()), 0), last(first.size(), 0);
    for (std::size_t e : {a, b, c})
      for (int n : mesh.element(static_cast<int>(e))) {
        auto& f = first[static_cast<std::size_t>(n)];
        f = f ? std::min(f, run.first[e]) : run.first[e];
        last[static_cast<std::size_t>(n)] = std::max(last[static_cast<std::size_t>(n)], run.last[e]);
      }
    const double m = 3.0 * mesh.node_count();
    EXPECT_EQ(static_cast<double>(plan.dofs.size()), m);
    std::vector<double> t_last, t_first;
    for (int j = 1; j < plan.stations; ++j) {
      t_last.push_back(3.0 * static_cast<double>(std::count_if(last.begin(), last.end(), [&](int l) { return l >= j; })));
      t_first.push_back(3.0 * static_cast<double>(std::count_if(first.begin(), first.end(), [&](int f) { return f <= j; })));
    }
    const double by_last = plan_flops(t_last, m), by_first = plan_flops(t_first, m);
    EXPECT_EQ(plan.by_first_change, by_first_expected);
    EXPECT_EQ(by_first < by_last, by_first_expected);
    EXPECT_NEAR(plan.refactorization_flops, std::min(by_first, by_last), 1e-9 * by_last);
    // Each node's three dofs together, in the chosen order.
    for (std::size_t i = 0; i < plan.dofs.size(); ++i) {
      EXPECT_EQ(plan.dofs[i] % 3, static_cast<int>(i % 3));
      if (i == 0) continue;
      const auto p = static_cast<std::size_t>(plan.dofs[i - 1] / 3), q = static_cast<std::size_t>(plan.dofs[i] / 3);
      if (by_first_expected) {
        EXPECT_GE(first[p], first[q]);
      } else {
        EXPECT_LE(last[p], last[q]);
      }
    }
    // It pays where a full factorization costs more than the block's dense work.
    EXPECT_TRUE(fem::ElasticProblem::block_pays(plan, m * m * m));
    EXPECT_FALSE(fem::ElasticProblem::block_pays(plan, 1.0));
    return plan;
  };
  // The tool crosses a, b, c in turn: by first change, station j refactorizes what it has touched.
  fem::RunChanges run{{0, 0, 0}, {0, 0, 0}};
  run.first[a] = run.last[a] = 1, run.first[b] = run.last[b] = 2, run.first[c] = run.last[c] = 3;
  EXPECT_EQ(check(run, true).stations, 4);
  // a and b go at once, c over two stations: by last change, station 2 refactorizes c's dofs alone.
  run.first[a] = run.last[a] = 1, run.first[b] = run.last[b] = 1, run.first[c] = 1, run.last[c] = 2;
  EXPECT_EQ(check(run, false).stations, 3);
  // A change before the first one is the caller's error.
  run.first[c] = 3;
  EXPECT_THROW(fem::ElasticProblem::plan_block(mesh, run), std::invalid_argument);
}
