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
  // The anchor itself, then the block's stiffness lowered step by step, as material goes.
  for (double softness : {1.0, 0.6, 0.2, 1e-3}) {
    const Eigen::SparseMatrix<double> changed = laplacian(g, in_block, softness);
    ASSERT_TRUE(solver.refactorize(solver.anchor_schur() + block_of(changed, block) - block_of(anchor, block)));
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

TEST(TrailingBlockCholesky, RefusesAnIndefiniteBlockAndKeepsThePreviousOne) {
  const Grid g{6, 6, 4};
  std::vector<char> in_block(static_cast<std::size_t>(g.size()), 0);
  std::vector<int> block;
  for (int d = 0; d < 10; ++d) in_block[static_cast<std::size_t>(d)] = 1, block.push_back(d);
  const Eigen::SparseMatrix<double> A = laplacian(g, in_block, 1.0);
  fem::TrailingBlockCholesky solver;
  ASSERT_TRUE(solver.factorize_anchor(A, block, fem::fill_reducing_ordering(A)));
  Eigen::MatrixXd indefinite = solver.anchor_schur();
  indefinite(3, 3) = -1;
  EXPECT_FALSE(solver.refactorize(indefinite));
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
  levelset::PartShape shape = levelset::PartShape::plate(60, 60, 6);
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
  fem::ElasticProblem problem() const {
    fem::ElasticProblem p(mesh, shape, {71700, 0.33}, profiles);
    p.set_fixed_dofs(clamped);
    return p;
  }
};

// Station k of a run: the first factorizes with the changing elements' dofs last, the others
// refactorize that block.
void factorize_station(fem::ElasticProblem& block, const std::vector<double>& activity, std::size_t k, const std::vector<char>& changing) {
  block.set_activity(activity);
  if (k == 0)
    block.assemble_and_factorize_anchor(changing);
  else
    block.refactorize_changed();
}

}  // namespace

TEST(BlockRefactorization, GivesTheFullFactorizationsDisplacementsAsMaterialGoes) {
  const MachinedPlate plate;
  fem::ElasticProblem full = plate.problem(), block = plate.problem();
  full.equilibrate(fem::isostatic_dofs(plate.mesh, plate.shape, std::vector<char>(static_cast<std::size_t>(plate.mesh.node_count()), 1)));
  block.adopt_equilibrium(full);
  full.measure_full_residuals(true);
  for (std::size_t k = 0; k < plate.stations.size(); ++k) {
    full.set_activity(plate.stations[k]);
    full.assemble_and_factorize();
    factorize_station(block, plate.stations[k], k, plate.pocket);
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
  full.equilibrate(fem::isostatic_dofs(plate.mesh, plate.shape, std::vector<char>(static_cast<std::size_t>(plate.mesh.node_count()), 1)));
  block.adopt_equilibrium(full);
  block.set_residual_bound(1e-300);
  for (std::size_t k = 0; k < plate.stations.size(); ++k) {
    full.set_activity(plate.stations[k]);
    full.assemble_and_factorize();
    factorize_station(block, plate.stations[k], k, plate.pocket);
    EXPECT_TRUE(block.solve() == full.solve()) << "station " << k;
  }
  // Every station's block solve failed the check and was solved again in full; the next station still
  // refactorized its block first.
  EXPECT_EQ(block.block_stats().residual_fallbacks, 4);
  EXPECT_EQ(block.block_stats().block_refactorizations, 3);
  EXPECT_EQ(block.solver_stats().factorizations, 4);
}

TEST(BlockRefactorization, ABlockTooLargeToPayFactorizesInFull) {
  // Every element flagged as changing: the block is the whole mesh, whose dense refactorization
  // would cost far more than a full one. The run factorizes in full, bit for bit the full path.
  const MachinedPlate plate;
  fem::ElasticProblem full = plate.problem(), block = plate.problem();
  full.equilibrate(fem::isostatic_dofs(plate.mesh, plate.shape, std::vector<char>(static_cast<std::size_t>(plate.mesh.node_count()), 1)));
  block.adopt_equilibrium(full);
  const std::vector<char> everything(static_cast<std::size_t>(plate.mesh.element_count()), 1);
  for (std::size_t k = 0; k < plate.stations.size(); ++k) {
    full.set_activity(plate.stations[k]);
    full.assemble_and_factorize();
    factorize_station(block, plate.stations[k], k, everything);
    EXPECT_TRUE(block.solve() == full.solve()) << "station " << k;
  }
  EXPECT_EQ(block.block_stats().full_chunks, 1);
  EXPECT_EQ(block.block_stats().anchors, 0);
  EXPECT_EQ(block.block_stats().block_refactorizations, 0);
  EXPECT_EQ(block.solver_stats().factorizations, 4);
}
