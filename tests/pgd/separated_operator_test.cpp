// The 2D operators the solver factorizes must be the 3D operator restricted to the trial space: for
// any plane functions X on thickness functions Z, the 2D matrix times X equals (K u) projected on Z,
// with K u computed independently by subtract_product. Checked on a plate and a panel, with an
// indicator, clamps (penalty) and the foundation.
#include "pgd/separated_operator.hpp"

#include <gtest/gtest.h>

#include <random>

using namespace drom;

namespace {

void check_restriction(const pgd::TensorGrid& grid, std::array<int, 3> functions) {
  pgd::SeparatedOperator op(grid, fem::Material{71700.0, 0.33});
  Eigen::VectorXd plane = Eigen::VectorXd::Zero(grid.plane_elements()), thickness = Eigen::VectorXd::Zero(grid.nt);
  for (int e = 0; e < grid.plane_elements(); e += 3) plane[e] = 1;
  thickness[grid.nt - 1] = 0.5;
  pgd::MaterialIndicator indicator;
  indicator.removed_plane.push_back(plane);
  indicator.removed_thickness.push_back(thickness);
  op.set_indicator(indicator);
  pgd::PenaltyTerm clamp{1, Eigen::VectorXd::Zero(grid.plane_nodes()), Eigen::VectorXd::Zero(grid.thickness_nodes())};
  clamp.plane.head(5).setOnes();
  clamp.thickness[0] = 1;
  op.set_penalty({clamp}, 1e3);
  op.set_foundation(1e-3);

  std::mt19937 rng(7);
  std::normal_distribution<double> normal;
  auto random = [&](Eigen::Index r, Eigen::Index c) -> Eigen::MatrixXd { return Eigen::MatrixXd::NullaryExpr(r, c, [&] { return normal(rng); }); };
  pgd::SeparatedField u = pgd::SeparatedField::empty(grid);
  for (std::size_t i = 0; i < 3; ++i) {
    u.X[i] = random(grid.plane_nodes(), functions[i]);
    u.Z[i] = random(grid.thickness_nodes(), functions[i]);
  }
  pgd::ComponentTensors Ku = pgd::zero_tensors(grid);
  op.subtract_product(u, Ku);
  for (auto& t : Ku) t = -t;
  const Eigen::VectorXd expected = op.plane_load(Ku, u.Z);

  const Eigen::VectorXd x = op.plane_vector(u.X);
  const auto unpacked = op.plane_functions(x, u.Z);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_EQ(unpacked[i], u.X[i]);
  const Eigen::SparseMatrix<double>& K2 = op.plane_matrix(u.Z);
  const Eigen::VectorXd got = K2.selfadjointView<Eigen::Lower>() * x;
  // The solver's diagonal shift is 1e-14 of each block: far below this tolerance.
  EXPECT_LT((got - expected).norm(), 1e-10 * expected.norm()) << "functions " << functions[0] << " " << functions[1] << " " << functions[2];
}

}  // namespace

TEST(SeparatedOperator, PlaneMatrixIsTheRestrictionOfTheOperatorOnAPlate) {
  const auto grid = pgd::TensorGrid::make(fem::PartShape::plate(100, 80, 6), 4, 3, 3);
  check_restriction(grid, {1, 1, 1});
  check_restriction(grid, {3, 2, 4});
}

TEST(SeparatedOperator, PlaneMatrixIsTheRestrictionOfTheOperatorOnAPanel) {
  const auto grid = pgd::TensorGrid::make(fem::PartShape::panel(120, 90, 4, 500), 4, 3, 3);
  check_restriction(grid, {1, 1, 1});
  check_restriction(grid, {2, 3, 1});
}
