// Issue 2 checks: patch test, intact stock, layer removal against the closed form, superposition.
#include "fem/elastic_problem.hpp"
#include "fem/layer_removal.hpp"
#include "fem/node_sets.hpp"
#include "fem/structured_mesh.hpp"
#include "fem/supports.hpp"
#include "fem/tet_mesh.hpp"

#include <Eigen/SparseCholesky>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

using namespace drom::fem;

namespace {

std::string sci(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.2e", v);
  return buf;
}

const Material kAluminium{71700.0, 0.33};

// Moves every corner node off the lattice (interior ones only, to keep the part's faces planar),
// then puts midside nodes back at their edge midpoints: straight-edged, distorted elements.
void distort(Mesh& mesh, double amplitude, unsigned seed) {
  Eigen::Vector3d lo = mesh.nodes[0], hi = lo;
  for (const auto& p : mesh.nodes) { lo = lo.cwiseMin(p); hi = hi.cwiseMax(p); }
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-amplitude, amplitude);
  const int corners = is_hex(mesh.type) ? 8 : 4;
  std::vector<char> is_corner(static_cast<std::size_t>(mesh.node_count()), 0);
  for (int e = 0; e < mesh.element_count(); ++e)
    for (int a = 0; a < corners; ++a) is_corner[static_cast<std::size_t>(mesh.element(e)[static_cast<std::size_t>(a)])] = 1;
  for (int n = 0; n < mesh.node_count(); ++n) {
    auto& p = mesh.nodes[static_cast<std::size_t>(n)];
    const bool interior = ((p - lo).minCoeff() > 1e-9) && ((hi - p).minCoeff() > 1e-9);
    if (is_corner[static_cast<std::size_t>(n)] && interior) p += Eigen::Vector3d(u(rng), u(rng), u(rng));
  }
  const std::vector<std::pair<int, int>> hex_edges = {{0, 1}, {1, 2}, {2, 3}, {3, 0}, {4, 5}, {5, 6}, {6, 7}, {7, 4}, {0, 4}, {1, 5}, {2, 6}, {3, 7}};
  const std::vector<std::pair<int, int>> tet_edges = {{0, 1}, {1, 2}, {0, 2}, {0, 3}, {1, 3}, {2, 3}};
  const auto& edges = is_hex(mesh.type) ? hex_edges : tet_edges;
  for (int e = 0; e < mesh.element_count(); ++e) {
    const auto c = mesh.element(e);
    for (std::size_t k = 0; k < edges.size(); ++k)
      mesh.nodes[static_cast<std::size_t>(c[static_cast<std::size_t>(corners) + k])] =
          0.5 * (mesh.nodes[static_cast<std::size_t>(c[static_cast<std::size_t>(edges[k].first)])] +
                 mesh.nodes[static_cast<std::size_t>(c[static_cast<std::size_t>(edges[k].second)])]);
    if (mesh.type != ElementType::Hex27) continue;
    // Face centres (-x, +x, -y, +y, -z, +z) and body centre at the means of their corners.
    const int faces[6][4] = {{0, 3, 4, 7}, {1, 2, 5, 6}, {0, 1, 4, 5}, {2, 3, 6, 7}, {0, 1, 2, 3}, {4, 5, 6, 7}};
    auto at = [&](int a) -> Eigen::Vector3d& { return mesh.nodes[static_cast<std::size_t>(c[static_cast<std::size_t>(a)])]; };
    for (int f = 0; f < 6; ++f) at(20 + f) = 0.25 * (at(faces[f][0]) + at(faces[f][1]) + at(faces[f][2]) + at(faces[f][3]));
    Eigen::Vector3d centre = Eigen::Vector3d::Zero();
    for (int a = 0; a < 8; ++a) centre += at(a) / 8;
    at(26) = centre;
  }
}

// Solves K u = 0 inside with u = A x + b prescribed on the boundary; returns max error inside.
double patch_test_error(const Mesh& mesh) {
  ElementOperators ops(mesh, kAluminium);
  StiffnessPattern pattern(mesh);
  Eigen::SparseMatrix<double> K = pattern.zero_matrix();
  for (int e = 0; e < mesh.element_count(); ++e) pattern.add_element(K, mesh.element(e), ops.stiffness(e), 1.0);
  const Eigen::SparseMatrix<double> Kfull = K.selfadjointView<Eigen::Lower>();

  Eigen::Matrix3d A;
  A << 1e-3, 2e-4, -3e-4, 5e-4, -2e-3, 1e-4, -4e-4, 3e-4, 1.5e-3;
  const Eigen::Vector3d b(0.01, -0.02, 0.03);
  Eigen::VectorXd exact(mesh.dof_count());
  for (int n = 0; n < mesh.node_count(); ++n) exact.segment<3>(3 * n) = A * mesh.nodes[static_cast<std::size_t>(n)] + b;

  const auto boundary = face_nodes_where(mesh, boundary_faces(mesh), [](const Eigen::Vector3d&) { return true; });
  std::vector<char> on_boundary(static_cast<std::size_t>(mesh.node_count()), 0);
  for (int n : boundary) on_boundary[static_cast<std::size_t>(n)] = 1;
  std::vector<int> inner_dofs, index(static_cast<std::size_t>(mesh.dof_count()), -1);
  for (int d = 0; d < mesh.dof_count(); ++d)
    if (!on_boundary[static_cast<std::size_t>(d / 3)]) {
      index[static_cast<std::size_t>(d)] = static_cast<int>(inner_dofs.size());
      inner_dofs.push_back(d);
    }
  if (inner_dofs.empty()) return INFINITY;
  const auto ni = static_cast<Eigen::Index>(inner_dofs.size());
  std::vector<Eigen::Triplet<double>> t;
  Eigen::VectorXd rhs = Eigen::VectorXd::Zero(ni);
  for (int c = 0; c < Kfull.outerSize(); ++c)
    for (Eigen::SparseMatrix<double>::InnerIterator it(Kfull, c); it; ++it) {
      const int r = index[static_cast<std::size_t>(it.row())];
      if (r < 0) continue;
      const int cc = index[static_cast<std::size_t>(c)];
      if (cc >= 0) t.emplace_back(r, cc, it.value());
      else rhs[r] -= it.value() * exact[c];
    }
  Eigen::SparseMatrix<double> Kii(ni, ni);
  Kii.setFromTriplets(t.begin(), t.end());
  Eigen::SimplicialLDLT<Eigen::SparseMatrix<double>> ldlt(Kii);
  const Eigen::VectorXd ui = ldlt.solve(rhs);
  double err = 0;
  for (Eigen::Index i = 0; i < ni; ++i) err = std::max(err, std::abs(ui[i] - exact[inner_dofs[static_cast<std::size_t>(i)]]));
  return err / (A.cwiseAbs().maxCoeff() * 10.0);
}

StressProfile biaxial(const std::vector<int>& degrees, const std::vector<double>& coefficients) {
  return {degrees, coefficients, coefficients};
}

}  // namespace

TEST(PatchTest, DistortedHex20ReproducesLinearField) {
  Mesh mesh = make_structured_hex_mesh(PartShape::plate(10, 10, 10), {3, 3, 3, 1.0});
  distort(mesh, 0.8, 7);
  for (double v : element_volumes(mesh)) ASSERT_GT(v, 0);
  const double err = patch_test_error(mesh);
  RecordProperty("relative_error", sci(err));
  EXPECT_LT(err, 1e-10);
}

TEST(PatchTest, DistortedHex27ReproducesLinearField) {
  Mesh mesh = make_structured_hex_mesh(PartShape::plate(10, 10, 10), {3, 3, 3, 1.0, ElementType::Hex27});
  distort(mesh, 0.8, 7);
  for (double v : element_volumes(mesh)) ASSERT_GT(v, 0);
  const double err = patch_test_error(mesh);
  RecordProperty("relative_error", sci(err));
  EXPECT_LT(err, 1e-10);
}

TEST(PatchTest, DistortedTet10ReproducesLinearField) {
  Mesh mesh = make_tet_mesh(layered_box_plc({0, 0, 0}, {10, 10, 10}, {}), {4.0, 1.4, 0});
  distort(mesh, 0.2, 11);
  for (double v : element_volumes(mesh)) ASSERT_GT(v, 0);
  const double err = patch_test_error(mesh);
  RecordProperty("relative_error", sci(err));
  EXPECT_LT(err, 1e-10);
}

namespace {
// A free plate: equilibrate, then hold it 3-2-1 for the subsequent solve.
struct FreePlate {
  Mesh mesh;
  PartShape shape;
};

double max_abs(const Eigen::MatrixXd& m) { return m.cwiseAbs().maxCoeff(); }
}  // namespace

TEST(IntactStock, ClampedHex20PlateDoesNotMove) {
  const PartShape shape = PartShape::plate(200, 150, 10);
  const Mesh mesh = make_structured_hex_mesh(shape, {10, 8, 4, 2.0});
  // A realistic rolled-plate M profile (MPa) plus odd content, different in both directions.
  const StressProfile profile{{2, 3, 4, 6}, {-120, 15, 40, -10}, {-80, -20, 25, 5}};
  ElasticProblem problem(mesh, shape, kAluminium, {profile});
  const std::vector<char> all(static_cast<std::size_t>(mesh.node_count()), 1);
  problem.equilibrate(isostatic_dofs(mesh, shape, all));
  EXPECT_LT(problem.equilibrium_residual(), 1e-9);
  EXPECT_GT(max_abs(problem.equilibration_displacement()), 1e-4);  // sigma_R was not traction-free
  const auto faces = boundary_faces(mesh);
  problem.set_fixed_dofs(node_dofs(face_nodes_where(mesh, faces, [](const Eigen::Vector3d& c) { return c.z() < 1e-9; })));
  problem.assemble_and_factorize();
  const double moved = max_abs(problem.solve());
  RecordProperty("max_displacement_mm", sci(moved));
  EXPECT_LT(moved, 1e-9);
}

TEST(IntactStock, ClampedPanelAndTetPartDoNotMove) {
  const PartShape panel = PartShape::panel(300, 200, 4.5, 1750);
  const Mesh hex = make_structured_hex_mesh(panel, {12, 8, 3, 1.0});
  const PartShape block = PartShape::block({0, 0, 0}, {60, 40, 6});
  const Mesh tet = make_tet_mesh(layered_box_plc({0, 0, 0}, {60, 40, 6}, {}), {20.0, 1.4, 0});
  const StressProfile odd{{3, 5}, {60, -20}, {30, 10}};
  for (const auto& mesh_and_shape : {std::pair{&hex, &panel}, std::pair{&tet, &block}}) {
    const Mesh* mesh = mesh_and_shape.first;
    const PartShape* shape = mesh_and_shape.second;  // a plain local: clang 14 cannot capture a structured binding
    ElasticProblem problem(*mesh, *shape, kAluminium, {odd});
    problem.equilibrate(isostatic_dofs(*mesh, *shape, std::vector<char>(static_cast<std::size_t>(mesh->node_count()), 1)));
    const auto faces = boundary_faces(*mesh);
    problem.set_fixed_dofs(node_dofs(face_nodes_where(*mesh, faces, [&](const Eigen::Vector3d& c) {
      const double u = shape->to_parametric(c).x();
      return u < 1e-6 || u > shape->length_u() - 1e-6;
    })));
    problem.assemble_and_factorize();
    EXPECT_LT(max_abs(problem.solve()), 1e-9) << element_name(mesh->type);
  }
}

namespace {
struct LayerResult {
  Eigen::Vector2d fe, exact;
};

LayerResult layer_removal(const Mesh& mesh, const PartShape& shape, const StressProfile& profile, double depth, RemovalCriterion crit) {
  ElasticProblem problem(mesh, shape, kAluminium, {profile});
  problem.equilibrate(isostatic_dofs(mesh, shape, std::vector<char>(static_cast<std::size_t>(mesh.node_count()), 1)));
  problem.set_activity(layer_activity(mesh, shape, depth, crit));
  problem.set_fixed_dofs(isostatic_dofs(mesh, shape, problem.live_nodes()));
  problem.assemble_and_factorize();
  const Eigen::VectorXd u = problem.solve().col(0);
  // Bottom face, central 40 %: away from the free edges' boundary layer.
  const auto nodes = nodes_where(mesh, [&](const Eigen::Vector3d& p) {
    return p.z() < 1e-9 && std::abs(p.x() - shape.length_u() / 2) < 0.2 * shape.length_u() &&
           std::abs(p.y() - shape.length_v() / 2) < 0.2 * shape.length_v();
  });
  const auto exact = layer_removal_closed_form(profile, shape.thickness(), depth, kAluminium.young_modulus, kAluminium.poisson_ratio);
  return {fit_plate_curvature(mesh, nodes, u), exact.curvature};
}

double relative_error(const LayerResult& r) { return (r.fe - r.exact).cwiseAbs().maxCoeff() / r.exact.cwiseAbs().maxCoeff(); }
}  // namespace

TEST(LayerRemoval, Hex20CurvatureMatchesClosedForm) {
  const PartShape shape = PartShape::plate(100, 100, 10);
  const StressProfile profile = biaxial({2, 4}, {-100, 40});
  const auto r = layer_removal(make_structured_hex_mesh(shape, {20, 20, 5, 1.0}), shape, profile, 2.0, RemovalCriterion::Centroid);
  RecordProperty("kappa_fe", std::to_string(r.fe.x()));
  RecordProperty("kappa_exact", std::to_string(r.exact.x()));
  RecordProperty("relative_error", sci(relative_error(r)));
  EXPECT_LT(relative_error(r), 0.01) << r.fe.transpose() << " vs " << r.exact.transpose();
  EXPECT_GT(std::abs(r.exact.x()), 1e-6);
}

TEST(LayerRemoval, Hex20UnequalProfilesGiveBothCurvatures) {
  const PartShape shape = PartShape::plate(100, 100, 10);
  const StressProfile profile{{2, 4}, {-100, 40}, {60, -10}};
  const auto r = layer_removal(make_structured_hex_mesh(shape, {20, 20, 5, 1.0}), shape, profile, 2.0, RemovalCriterion::Centroid);
  EXPECT_LT(relative_error(r), 0.01) << r.fe.transpose() << " vs " << r.exact.transpose();
  EXPECT_LT(r.exact.x() * r.exact.y(), 0);  // opposite signs: a saddle
}

TEST(LayerRemoval, VolumeFractionMatchesCentroidOnAlignedMesh) {
  const PartShape shape = PartShape::plate(100, 100, 10);
  const Mesh mesh = make_structured_hex_mesh(shape, {20, 20, 5, 1.0});
  const StressProfile profile = biaxial({2, 4}, {-100, 40});
  const auto a = layer_removal(mesh, shape, profile, 2.0, RemovalCriterion::Centroid);
  const auto b = layer_removal(mesh, shape, profile, 2.0, RemovalCriterion::VolumeFraction);
  EXPECT_LT((a.fe - b.fe).norm() / a.fe.norm(), 1e-10);
}

TEST(LayerRemoval, Tet10CurvatureMatchesClosedForm) {
  const PartShape shape = PartShape::block({0, 0, 0}, {100, 100, 10});
  const StressProfile profile = biaxial({2, 4}, {-100, 40});
  const Mesh mesh = make_tet_mesh(layered_box_plc({0, 0, 0}, {100, 100, 10}, {8.0}), {12.0, 1.4, 0});
  const auto r = layer_removal(mesh, shape, profile, 2.0, RemovalCriterion::Centroid);
  RecordProperty("tets", mesh.element_count());
  RecordProperty("relative_error", sci(relative_error(r)));
  EXPECT_LT(relative_error(r), 0.02) << r.fe.transpose() << " vs " << r.exact.transpose();
}

TEST(Superposition, ProfileResponseIsWeightedSumOfUnitResponses) {
  const PartShape shape = PartShape::plate(120, 80, 8);
  const Mesh mesh = make_structured_hex_mesh(shape, {12, 8, 4, 1.0});
  const std::vector<int> degrees = legendre_degrees(ProfileParity::Even, 6);
  const StressProfile profile{degrees, {-110, 35, -8}, {-70, 20, 12}};
  auto solve = [&](const std::vector<StressProfile>& profiles) {
    ElasticProblem problem(mesh, shape, kAluminium, profiles);
    problem.equilibrate(isostatic_dofs(mesh, shape, std::vector<char>(static_cast<std::size_t>(mesh.node_count()), 1)));
    problem.set_activity(layer_activity(mesh, shape, 2.0, RemovalCriterion::Centroid));
    const auto faces = boundary_faces(mesh);
    problem.set_fixed_dofs(node_dofs(face_nodes_where(mesh, faces, [](const Eigen::Vector3d& c) { return c.x() < 1e-9; })));
    problem.assemble_and_factorize();
    return problem.solve();
  };
  const Eigen::MatrixXd units = solve(unit_profiles(degrees));
  const Eigen::VectorXd direct = solve({profile}).col(0);
  const Eigen::VectorXd combined = units * profile_weights(profile);
  EXPECT_GT(direct.cwiseAbs().maxCoeff(), 1e-3);
  const double err = (combined - direct).cwiseAbs().maxCoeff() / direct.cwiseAbs().maxCoeff();
  RecordProperty("relative_error", sci(err));
  EXPECT_LT(err, 1e-10);
}
