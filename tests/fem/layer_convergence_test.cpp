// Issue 2 check 3, refinement: the free plate's curvature after layer removal converges to the
// closed form. Two studies, with the observed orders recorded as test properties:
//  - in-plane refinement with the cut on an element face (error from the 3D edge zone only);
//  - through-thickness refinement with the cut inside elements (3 elements through 10 mm, cut at
//    8 mm), where the removal criterion matters: centroid vs volume fraction.
#include "fem/elastic_problem.hpp"
#include "fem/layer_removal.hpp"
#include "fem/node_sets.hpp"
#include "fem/structured_mesh.hpp"
#include "fem/supports.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

using namespace drom::fem;

namespace {

double curvature_error(int n_inplane, int nz, RemovalCriterion criterion) {
  const PartShape shape = PartShape::plate(100, 100, 10);
  const Mesh mesh = make_structured_hex_mesh(shape, {n_inplane, n_inplane, nz, 1.0});
  const StressProfile profile{{2, 4}, {-100, 40}, {-100, 40}};
  const Material material{71700, 0.33};
  ElasticProblem problem(mesh, shape, material, {profile});
  problem.equilibrate(isostatic_dofs(mesh, shape, std::vector<char>(static_cast<std::size_t>(mesh.node_count()), 1)));
  problem.set_activity(layer_activity(mesh, shape, 2.0, criterion));
  problem.set_fixed_dofs(isostatic_dofs(mesh, shape, problem.live_nodes()));
  problem.assemble_and_factorize();
  const Eigen::VectorXd u = problem.solve().col(0);
  const auto nodes = nodes_where(mesh, [](const Eigen::Vector3d& p) {
    return p.z() < 1e-9 && std::abs(p.x() - 50) < 20 && std::abs(p.y() - 50) < 20;
  });
  const double exact = layer_removal_closed_form(profile, 10, 2, material.young_modulus, material.poisson_ratio).curvature.x();
  const Eigen::Vector2d fe = fit_plate_curvature(mesh, nodes, u);
  return std::abs(fe.x() - exact) / std::abs(exact);
}

double order(double e_coarse, double e_fine) { return std::log(e_coarse / e_fine) / std::log(2.0); }

}  // namespace

TEST(LayerRemovalConvergence, InPlaneRefinementWithAlignedCut) {
  const double e5 = curvature_error(5, 5, RemovalCriterion::Centroid);
  const double e10 = curvature_error(10, 5, RemovalCriterion::Centroid);
  const double e20 = curvature_error(20, 5, RemovalCriterion::Centroid);
  std::printf("in-plane h = 20, 10, 5 mm: relative curvature error %.3e, %.3e, %.3e (orders %.2f, %.2f)\n", e5, e10, e20, order(e5, e10),
              order(e10, e20));
  RecordProperty("errors", std::to_string(e5) + " " + std::to_string(e10) + " " + std::to_string(e20));
  // Measured here: 1.1e-4, 7.9e-8, 6.7e-7. The error falls by three orders from h = 20 to 10 mm and
  // then sits at a ~1e-7 floor (the 3D edge zone and round-off), so below that the order is noise.
  EXPECT_LT(e5, 1e-3);
  EXPECT_LT(e10, e5 / 100);
  EXPECT_LT(e20, 1e-5);
}

TEST(LayerRemovalConvergence, ThicknessRefinementWithCutInsideElements) {
  // nz = 3, 6, 12: the cut plane z = 8 never lies on an element face.
  double centroid[3], fraction[3];
  const int nzs[3] = {3, 6, 12};
  for (int k = 0; k < 3; ++k) {
    centroid[k] = curvature_error(10, nzs[k], RemovalCriterion::Centroid);
    fraction[k] = curvature_error(10, nzs[k], RemovalCriterion::VolumeFraction);
  }
  std::printf("nz = 3, 6, 12, centroid: %.3e %.3e %.3e (orders %.2f, %.2f)\n", centroid[0], centroid[1], centroid[2], order(centroid[0], centroid[1]),
              order(centroid[1], centroid[2]));
  std::printf("nz = 3, 6, 12, volume fraction: %.3e %.3e %.3e (orders %.2f, %.2f)\n", fraction[0], fraction[1], fraction[2],
              order(fraction[0], fraction[1]), order(fraction[1], fraction[2]));
  // Measured here: volume fraction 0.68, 0.069, 0.0022 (order 3.3 then 4.9); the centroid
  // criterion removes whole elements, 0.84, 0.21, 0.21, and stops improving whenever the cut keeps
  // falling in the same half of an element.
  EXPECT_LT(fraction[1], fraction[0] / 4);
  EXPECT_LT(fraction[2], fraction[1] / 4);
  EXPECT_LT(fraction[2], 0.005);
  EXPECT_LT(fraction[2], centroid[2]);
}
