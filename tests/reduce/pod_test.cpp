// The POD's truncation bounds (seed eqs. 2.9, 2.12) and the space-time form of a history.
#include "reduce/pod.hpp"
#include "reduce/space_time_field.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace drom::reduce;

namespace {

// A family whose singular values decay smoothly: Gaussian bumps of varying centre and width, plus a
// tilt, sampled on 300 points (the seed's chapter 2 family in 1D).
Eigen::MatrixXd bump_family() {
  const int n = 300, m = 40;
  Eigen::MatrixXd A(n, m);
  for (int j = 0; j < m; ++j) {
    const double a = 0.2 + 0.6 * j / (m - 1.0), b = 0.05 + 0.1 * ((j * 7) % m) / m;
    for (int i = 0; i < n; ++i) {
      const double x = i / (n - 1.0);
      A(i, j) = 4 * std::exp(-(x - a) * (x - a) / b) + 2 * (0.76 - x) * (0.14 - a);
    }
  }
  return A;
}

}  // namespace

TEST(Pod, EverySnapshotsTruncationErrorIsWithinTheBound) {
  const Eigen::MatrixXd A = bump_family();
  for (double tolerance : {1.0, 1e-2, 1e-4, 1e-6}) {
    const Pod pod = truncated_pod(A, tolerance);
    EXPECT_LE(pod.max_bound, tolerance);
    const Eigen::MatrixXd E = A - pod.modes * (pod.modes.transpose() * A);
    double worst_max = 0, worst_l2 = 0;
    for (Eigen::Index j = 0; j < A.cols(); ++j) {
      EXPECT_LE(E.col(j).cwiseAbs().maxCoeff(), pod.max_bound * (1 + 1e-9) + 1e-12) << "snapshot " << j;
      EXPECT_LE(E.col(j).norm(), pod.euclidean_bound * (1 + 1e-9) + 1e-12) << "snapshot " << j;
      worst_max = std::max(worst_max, E.col(j).cwiseAbs().maxCoeff());
      worst_l2 = std::max(worst_l2, E.col(j).norm());
    }
    // The fewest modes: one fewer would break the tolerance.
    if (pod.rank() > 0) {
      EXPECT_GT(max_norm_bound(pod.singular_values, pod.rank() - 1), tolerance);
    }
    std::printf("tolerance %.0e: r = %d, bound %.2e (measured %.2e), l2 bound %.2e (measured %.2e)\n", tolerance, pod.rank(), pod.max_bound, worst_max,
                pod.euclidean_bound, worst_l2);
  }
}

TEST(Pod, EuclideanToleranceAndRankCap) {
  const Eigen::MatrixXd A = bump_family();
  const Pod l2 = truncated_pod(A, 1e-3, PodNorm::Euclidean);
  const Pod mx = truncated_pod(A, 1e-3, PodNorm::Max);
  EXPECT_LE(l2.euclidean_bound, 1e-3);
  EXPECT_LE(l2.rank(), mx.rank());  // the 2-norm bound is the smaller one
  const Pod capped = truncated_pod(A, 0, PodNorm::Max, 3);
  EXPECT_EQ(capped.rank(), 3);
  EXPECT_NEAR(capped.max_bound, capped.singular_values.tail(capped.singular_values.size() - 3).sum(), 1e-12);
  EXPECT_THROW(truncated_pod(A, std::nan("")), std::invalid_argument);
  Eigen::MatrixXd bad = A;
  bad(3, 4) = std::nan("");
  EXPECT_THROW(truncated_pod(bad, 1e-3), std::invalid_argument);
}

TEST(SpaceTimeField, SeparatedFormIsWithinItsBoundAndLinearBetweenInstants) {
  // A history over 200 nodes and 60 instants: three smooth separable parts and a small rough one.
  const int n = 200, m = 60;
  Eigen::MatrixXd H(n, m);
  Eigen::VectorXd times(m);
  for (int k = 0; k < m; ++k) times[k] = 1.0 + 0.5 * k + 0.1 * std::sin(k);
  for (int i = 0; i < n; ++i)
    for (int k = 0; k < m; ++k) {
      const double x = i / (n - 1.0), t = times[k] / times[m - 1];
      H(i, k) = x * t + std::sin(3 * x) * t * t + 0.1 * std::cos(5 * x) * std::sqrt(t) + 1e-5 * std::sin(37.0 * i * k);
    }
  const SpaceTimeField f(H, times, 1e-3, 0.0);
  EXPECT_LE(f.bound(), 1e-3);
  EXPECT_GE(f.terms(), 3);   // the three smooth parts at least...
  EXPECT_LT(f.terms(), m);   // ...and not the whole history
  double worst = 0;
  for (int k = 0; k < m; ++k) worst = std::max(worst, (f.at(times[k]) - H.col(k)).cwiseAbs().maxCoeff());
  EXPECT_LE(worst, f.bound() + 1e-12);
  // Halfway between two instants: the mean of the two (what linear interpolation of the full
  // history gives), to the same bound.
  const Eigen::VectorXd mid = f.at(0.5 * (times[10] + times[11])), expected = 0.5 * (H.col(10) + H.col(11));
  EXPECT_LE((mid - expected).cwiseAbs().maxCoeff(), f.bound() + 1e-12);
  // Before the first instant it goes linearly to 0 at the start; after the last it stays.
  EXPECT_NEAR(f.at(17, 0.0), 0.0, 1e-14);
  EXPECT_NEAR(f.at(17, 0.5 * times[0]), 0.5 * f.at(17, times[0]), 1e-12);
  EXPECT_NEAR(f.at(17, 1e9), f.at(17, times[m - 1]), 1e-14);
  std::printf("space-time: %d terms for 200 x 60, bound %.2e, measured %.2e\n", f.terms(), f.bound(), worst);
}

#include "reduce/deviation_family.hpp"
#include "support/input_error.hpp"

#include <filesystem>
#include <fstream>
#include <random>
#include <algorithm>

TEST(DeviationFamily, MeasuredSurfacesJoinTheFamilyAndBadFilesAreNamed) {
  // A measured blank (a tilted plane sampled on a coarse grid, with a header line) lands on the
  // family's grid exactly at its points and between them by inverse-distance weights.
  const auto csv = std::filesystem::temp_directory_path() / "drom_measured_blank.csv";
  {
    std::ofstream out(csv);
    out << "x,y,z\n";
    for (int j = 0; j <= 10; ++j)
      for (int i = 0; i <= 10; ++i) out << 10 * i << "," << 10 * j << "," << 5 + 0.01 * (10 * i) << "\n";
  }
  drom::reduce::DeviationFamily family(drom::reduce::DeviationGrid{0, 100, 0, 100, 11, 11});
  family.add_measured(csv, 5.0);
  ASSERT_EQ(family.size(), 1);
  const auto& g = family.grid();
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) EXPECT_NEAR(family.snapshots()(g.index(i, j), 0), 0.01 * g.x(i), 1e-12);
  {
    std::ofstream out(csv);
    out << "x,y,z\n1,2,3\n4,five,6\n";
  }
  try {
    family.add_measured(csv);
    FAIL() << "no error";
  } catch (const drom::InputError& e) {
    EXPECT_NE(std::string(e.what()).find(csv.string() + ":3"), std::string::npos) << e.what();
  }
  std::filesystem::remove(csv);
  EXPECT_THROW(family.add_measured(csv), drom::InputError);
}

TEST(DeviationFamily, APointMeasuredTwiceGivesTheMeanOfItsMeasurements) {
  const auto csv = std::filesystem::temp_directory_path() / "drom_measured_twice.csv";
  std::ofstream(csv) << "0,0,1\n0,0,3\n100,0,0\n0,100,0\n100,100,0\n";
  drom::reduce::DeviationFamily family(drom::reduce::DeviationGrid{0, 100, 0, 100, 2, 2});
  family.add_measured(csv);
  std::filesystem::remove(csv);
  EXPECT_DOUBLE_EQ(family.snapshots()(family.grid().index(0, 0), 0), 2.0);
  EXPECT_DOUBLE_EQ(family.snapshots()(family.grid().index(1, 1), 0), 0.0);
}

TEST(DeviationFamily, AScanOfManyPointsIsInterpolatedFromItsFourNearestAsAFullSearchWould) {
  // A scattered scan (not on the grid, so every grid value is a weighted mean of 4 neighbours):
  // each value must equal the inverse-distance mean over the 4 nearest found by checking every point.
  const auto csv = std::filesystem::temp_directory_path() / "drom_scattered_scan.csv";
  std::vector<Eigen::Vector3d> points;
  std::mt19937 random(7);
  std::uniform_real_distribution<double> across(-5, 105), wobble(-0.2, 0.2);
  {
    std::ofstream out(csv);
    out.precision(17);
    for (int k = 0; k < 3000; ++k) {
      const Eigen::Vector3d p(across(random), across(random), 2 + wobble(random));
      points.push_back(p);
      out << p.x() << "," << p.y() << "," << p.z() << "\n";
    }
  }
  drom::reduce::DeviationFamily family(drom::reduce::DeviationGrid{0, 100, 0, 100, 21, 17});
  family.add_measured(csv, 2.0);
  std::filesystem::remove(csv);
  const auto& g = family.grid();
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) {
      std::vector<std::pair<double, double>> by_distance;  // (squared distance in xy, deviation)
      for (const auto& p : points) by_distance.emplace_back((p.x() - g.x(i)) * (p.x() - g.x(i)) + (p.y() - g.y(j)) * (p.y() - g.y(j)), p.z() - 2.0);
      std::partial_sort(by_distance.begin(), by_distance.begin() + 4, by_distance.end());
      double w = 0, v = 0;
      for (int k = 0; k < 4; ++k) w += 1 / by_distance[k].first, v += by_distance[k].second / by_distance[k].first;
      EXPECT_NEAR(family.snapshots()(g.index(i, j), 0), v / w, 1e-12) << "at grid point " << i << ", " << j;
    }
}
