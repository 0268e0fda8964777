// Issue 28: a machining state written as a CalculiX deck holds that state (mesh, removed and partly
// machined elements, initial stress at ccx's integration points in ccx's order, clamps), and ccx's
// printed displacements are read back or refused with the file and line. The deck against ccx
// itself: tests/offline/calculix_export_test.cpp.
#include "fem/calculix_deck.hpp"
#include "fem/node_sets.hpp"
#include "fem/structured_mesh.hpp"
#include "fem/supports.hpp"
#include "support/input_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

using namespace drom;

namespace {

std::filesystem::path scratch(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() / ("drom_calculix_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(d);
  std::filesystem::create_directories(d);
  return d;
}

std::vector<std::string> lines_of(const std::filesystem::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

// The data lines under a keyword line that starts with `keyword` (up to the next keyword).
std::vector<std::string> card(const std::vector<std::string>& lines, const std::string& keyword) {
  std::vector<std::string> rows;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (lines[i].rfind(keyword, 0) != 0) continue;
    for (std::size_t j = i + 1; j < lines.size() && lines[j][0] != '*'; ++j) rows.push_back(lines[j]);
    return rows;
  }
  return rows;
}

std::vector<double> numbers(const std::string& row) {
  std::vector<double> values;
  std::stringstream s(row);
  for (std::string field; std::getline(s, field, ',');)
    if (!field.empty()) values.push_back(std::stod(field));
  return values;
}

void write_text(const std::filesystem::path& path, const std::string& text) { std::ofstream(path) << text; }

}  // namespace

TEST(CalculixDeck, IntegrationPointsFollowCcxOrder) {
  // What ccx 2.20 printed for *EL PRINT, COORD on one C3D20: the first reference coordinate fastest.
  const auto points = fem::c3d20_integration_points();
  ASSERT_EQ(points.size(), 27u);
  const double g = std::sqrt(0.6);
  EXPECT_LT((points[0] - Eigen::Vector3d(-g, -g, -g)).norm(), 1e-15);
  EXPECT_LT((points[1] - Eigen::Vector3d(0, -g, -g)).norm(), 1e-15);
  EXPECT_LT((points[3] - Eigen::Vector3d(-g, 0, -g)).norm(), 1e-15);
  EXPECT_LT((points[9] - Eigen::Vector3d(-g, -g, 0)).norm(), 1e-15);
  EXPECT_LT((points[26] - Eigen::Vector3d(g, g, g)).norm(), 1e-15);
}

TEST(CalculixDeck, HoldsTheMachiningStateItDescribes) {
  const geometry::PartShape shape = geometry::PartShape::plate(60, 40, 6);
  const fem::Mesh mesh = fem::make_structured_hex_mesh(shape, {3, 2, 2, 1.0});
  const fem::Material material{71700, 0.33};
  fem::StressProfile profile;
  profile.degrees = {2, 3};
  profile.sigma11 = {-50, 20};
  profile.sigma22 = {-30, 10};
  fem::ElasticProblem problem(mesh, shape, material, {profile});
  problem.equilibrate(fem::isostatic_dofs(mesh, shape, std::vector<char>(static_cast<std::size_t>(mesh.node_count()), 1)));
  std::vector<double> activity(static_cast<std::size_t>(mesh.element_count()), 1.0);
  activity[10] = 0.0;   // machined away
  activity[11] = 0.25;  // partly machined
  problem.set_activity(activity);
  const std::vector<int> fixed = {0, 1, 2, 7};
  problem.set_fixed_dofs(fixed);

  const auto dir = scratch("deck");
  const auto stats = fem::write_calculix_deck(dir / "s.inp", problem, material, 0, "a test station");
  EXPECT_EQ(stats.nodes, mesh.node_count());
  EXPECT_EQ(stats.elements, 12);
  EXPECT_EQ(stats.removed, 1);
  EXPECT_EQ(stats.partial, 1);
  EXPECT_EQ(stats.fixed_dofs, 4);
  const auto lines = lines_of(dir / "s.inp");
  for (std::size_t i = 0; i < lines.size(); ++i) EXPECT_LE(lines[i].size(), 132u) << "line " << i + 1;

  const auto nodes = card(lines, "*NODE, NSET=NALL");
  ASSERT_EQ(nodes.size(), static_cast<std::size_t>(mesh.node_count()));
  const auto node7 = numbers(nodes[6]);
  EXPECT_EQ(node7[0], 7);
  EXPECT_EQ((Eigen::Vector3d(node7[1], node7[2], node7[3]) - mesh.nodes[6]).norm(), 0.0);  // %.17g: exact

  // Each element on a line and its continuation, drom's node order unchanged.
  const auto elements = card(lines, "*ELEMENT, TYPE=C3D20");
  ASSERT_EQ(elements.size(), 24u);
  for (int e = 0; e < mesh.element_count(); ++e) {
    auto ids = numbers(elements[2 * static_cast<std::size_t>(e)]);
    const auto more = numbers(elements[2 * static_cast<std::size_t>(e) + 1]);
    ids.insert(ids.end(), more.begin(), more.end());
    ASSERT_EQ(ids.size(), 21u);
    EXPECT_EQ(ids[0], e + 1);
    for (std::size_t a = 0; a < 20; ++a) EXPECT_EQ(ids[a + 1], mesh.element(e)[a] + 1);
  }
  EXPECT_EQ(card(lines, "*ELSET, ELSET=REMOVED"), std::vector<std::string>{"11"});
  EXPECT_EQ(card(lines, "*ELSET, ELSET=P12"), std::vector<std::string>{"12"});
  bool found_partial = false;
  for (std::size_t i = 0; i + 2 < lines.size(); ++i)
    if (lines[i] == "*MATERIAL, NAME=P12") {
      EXPECT_EQ(lines[i + 1], "*ELASTIC");
      const auto v = numbers(lines[i + 2]);
      EXPECT_DOUBLE_EQ(v[0], 0.25 * 71700);
      EXPECT_DOUBLE_EQ(v[1], 0.33);
      found_partial = true;
    }
  EXPECT_TRUE(found_partial);

  // 27 rows per element left, none for the removed one; ccx's order xx yy zz xy xz yz, scaled by a.
  const auto stresses = card(lines, "*INITIAL CONDITIONS, TYPE=STRESS");
  ASSERT_EQ(stresses.size(), 27u * 11);
  const auto points = fem::c3d20_integration_points();
  std::map<std::pair<int, int>, std::vector<double>> by_point;
  for (const auto& row : stresses) {
    const auto v = numbers(row);
    ASSERT_EQ(v.size(), 8u);
    by_point[{static_cast<int>(v[0]), static_cast<int>(v[1])}] = v;
  }
  EXPECT_EQ(by_point.count({11, 1}), 0u);
  for (int e : {0, 5, 11}) {
    const double a = activity[static_cast<std::size_t>(e)];
    for (int q : {0, 4, 13, 26}) {
      const fem::Vector6d s = a * problem.initial_stress(0, e, points[static_cast<std::size_t>(q)]);
      const auto& v = by_point.at({e + 1, q + 1});
      const int voigt[6] = {0, 1, 2, 5, 4, 3};
      for (int i = 0; i < 6; ++i) EXPECT_NEAR(v[static_cast<std::size_t>(2 + i)], s(voigt[i]), 1e-9 * (1 + std::abs(s(voigt[i])))) << e << " " << q << " " << i;
    }
  }
  // The step removes the machined set and holds the fixed dofs.
  EXPECT_EQ(card(lines, "*MODEL CHANGE, TYPE=ELEMENT, REMOVE"), std::vector<std::string>{"REMOVED"});
  EXPECT_EQ(card(lines, "*BOUNDARY"), (std::vector<std::string>{"1,1,1,0", "1,2,2,0", "1,3,3,0", "3,2,2,0"}));
  std::filesystem::remove_all(dir);
}

TEST(CalculixDeck, RefusesMeshesCcxCannotHoldAndUnequilibratedProblems) {
  const geometry::PartShape shape = geometry::PartShape::plate(20, 20, 4);
  fem::StressProfile profile;
  profile.degrees = {2};
  profile.sigma11 = {-50};
  profile.sigma22 = {-30};
  const auto dir = scratch("refuse");
  const fem::Mesh hex27 = fem::make_structured_hex_mesh(shape, {2, 2, 1, 1.0, fem::ElementType::Hex27});
  fem::ElasticProblem p27(hex27, shape, {71700, 0.33}, {profile});
  p27.equilibrate(fem::isostatic_dofs(hex27, shape, std::vector<char>(static_cast<std::size_t>(hex27.node_count()), 1)));
  EXPECT_THROW(fem::write_calculix_deck(dir / "a.inp", p27, {71700, 0.33}, 0, "x"), std::invalid_argument);
  const fem::Mesh hex20 = fem::make_structured_hex_mesh(shape, {2, 2, 1, 1.0});
  fem::ElasticProblem p20(hex20, shape, {71700, 0.33}, {profile});
  EXPECT_THROW(fem::write_calculix_deck(dir / "b.inp", p20, {71700, 0.33}, 0, "x"), std::logic_error);  // not equilibrated
  p20.equilibrate(fem::isostatic_dofs(hex20, shape, std::vector<char>(static_cast<std::size_t>(hex20.node_count()), 1)));
  EXPECT_THROW(fem::write_calculix_deck(dir / "c.inp", p20, {71700, 0.33}, 1, "x"), std::invalid_argument);  // no profile 1
  EXPECT_FALSE(std::filesystem::exists(dir / "a.inp") || std::filesystem::exists(dir / "b.inp") || std::filesystem::exists(dir / "c.inp"));
  std::filesystem::remove_all(dir);
}

TEST(CalculixDeck, ReadsPrintedDisplacementsAndNamesBadRows) {
  const auto dir = scratch("dat");
  const std::string header = "\n displacements (vx,vy,vz) for set NALL and time  0.1000000E+01\n\n";
  write_text(dir / "ok.dat", header + "         1  1.000000E-03  0.000000E+00 -2.500000E-01\n         3  4.000000E+00  5.000000E+00  6.000000E+00\n\n" + header +
                                 "         1  9.000000E+00  9.000000E+00  9.000000E+00\n");
  const Eigen::VectorXd u = fem::read_calculix_displacements(dir / "ok.dat", 3);
  ASSERT_EQ(u.size(), 9);
  EXPECT_EQ(u(0), 1e-3);
  EXPECT_EQ(u(2), -0.25);
  EXPECT_EQ(u.segment<3>(3), Eigen::Vector3d::Zero());  // not printed: zero
  EXPECT_EQ(u(8), 6.0);                                  // the first block only

  auto message = [&](const std::string& name, const std::string& text, int nodes) {
    write_text(dir / name, text);
    try {
      fem::read_calculix_displacements(dir / name, nodes);
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string("no error");
  };
  EXPECT_NE(message("short.dat", header + "  1  1.0  2.0\n", 3).find("short.dat:4: expected \"node ux uy uz\""), std::string::npos);
  EXPECT_NE(message("nan.dat", header + "  1  1.0  nan  2.0\n", 3).find("nan.dat:4"), std::string::npos);
  EXPECT_NE(message("range.dat", header + "  4  1.0  2.0  3.0\n", 3).find("range.dat:4: node 4 is outside 1..3"), std::string::npos);
  EXPECT_NE(message("twice.dat", header + "  2  1.0  2.0  3.0\n  2  1.0  2.0  3.0\n", 3).find("twice.dat:5: node 2 printed twice"), std::string::npos);
  EXPECT_NE(message("none.dat", " stresses (elem, integ.pnt.,sxx,syy,szz,sxy,sxz,syz)\n", 3).find("none.dat: no \"displacements"), std::string::npos);
  EXPECT_THROW(fem::read_calculix_displacements(dir / "missing.dat", 3), InputError);
  std::filesystem::remove_all(dir);
}
