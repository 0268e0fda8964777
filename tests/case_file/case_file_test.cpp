// Case files: every bad input names its key (and line), every key can be overridden with --set.
#include "case_file/case.hpp"
#include "offline/part_setup.hpp"
#include "support/input_error.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

using drom::InputError;
using drom::case_file::load_case;

namespace {

std::string error_of(const std::vector<std::string>& overrides, const std::optional<std::filesystem::path>& path = std::nullopt) {
  try {
    load_case(path, overrides);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

std::filesystem::path write_temp(const std::string& name, const std::string& text) {
  const auto dir = std::filesystem::temp_directory_path() / "drom_case_tests";
  std::filesystem::create_directories(dir);
  std::ofstream(dir / name) << text;
  return dir / name;
}

}  // namespace

TEST(CaseFile, EmbeddedDefaultIsTheFlatPlate) {
  const auto c = load_case(std::nullopt, {});
  EXPECT_EQ(c.name, "flat_plate");
  EXPECT_EQ(c.length_x, 1000.0);
  EXPECT_EQ(c.pocket_depth, 2.0);
  EXPECT_EQ(c.clamps.size(), 4u);
  EXPECT_EQ(c.sigma11.size(), 3u);  // P2, P4, P6
}

TEST(CaseFile, ShippedCasesLoad) {
  for (const char* name : {"flat_plate.toml", "curved_panel.toml"}) {
    const auto c = load_case(std::filesystem::path(DROM_SOURCE_DIR) / "cases" / name, {});
    EXPECT_FALSE(c.name.empty());
  }
}

TEST(CaseFile, OverridesReachEveryKindOfValue) {
  const auto c = load_case(std::nullopt, {"mesh.nx=12", "part.thickness=12.5", "stress.sigma11=[1, 2, 3]", "clamps.1.face=top",
                                          "removal.criterion=centroid", "mesh.thickness_grading=2"});
  EXPECT_EQ(c.nx, 12);
  EXPECT_EQ(c.thickness, 12.5);
  EXPECT_EQ(c.sigma11, (std::vector<double>{1, 2, 3}));
  EXPECT_EQ(c.clamps[1].face, "top");
  EXPECT_EQ(c.removal_criterion, "centroid");
  EXPECT_EQ(c.thickness_grading, 2.0);
  EXPECT_NE(c.resolved_toml.find("12.5"), std::string::npos);
}

TEST(CaseFile, UnknownKeysAreRejectedByName) {
  EXPECT_NE(error_of({"mesh.nxx=3"}).find("mesh.nxx: unknown key"), std::string::npos);
  EXPECT_NE(error_of({"tool.colour='red'"}).find("tool.colour: unknown key"), std::string::npos);
  const auto path = write_temp("typo.toml", std::string(drom::case_file::embedded_default_case()) + "\n[material]\n");
  // A duplicated table is a TOML error with its line.
  EXPECT_NE(error_of({}, path).find("typo.toml:"), std::string::npos);
  const auto typo = write_temp("typo2.toml", "name = 'x'\n[part]\nshape = 'plate'\nlenght_x = 3\n");
  EXPECT_NE(error_of({}, typo).find("part.length_x"), std::string::npos);  // missing comes first
}

TEST(CaseFile, SolverSectionChoosesPgdWithItsTolerances) {
  // The default case meshes with hex20: the PGD's tensor space is hex27, and the error says so.
  EXPECT_NE(error_of({"solver.kind=pgd"}).find("mesh.element"), std::string::npos);
  EXPECT_NE(error_of({"solver.kind=pgd"}).find("hex27"), std::string::npos);
  // PGD settings without the PGD are a mistake, not silently ignored.
  EXPECT_NE(error_of({"solver.max_modes=10"}).find("solver.max_modes: is a setting of the PGD solver"), std::string::npos);
  EXPECT_NE(error_of({"solver.kind='bem'"}).find("solver.kind"), std::string::npos);
  const auto c = load_case(std::nullopt, {"solver.kind=pgd", "mesh.element=hex27", "solver.residual_tolerance=1e-5", "solver.max_modes=40",
                                          "solver.anderson_depth=0", "solver.update_every=2", "solver.penalty=1e9"});
  EXPECT_EQ(c.solver, "pgd");
  EXPECT_EQ(c.pgd.residual_tolerance.value(), 1e-5);
  EXPECT_EQ(c.pgd.max_modes.value(), 40);
  EXPECT_EQ(c.pgd.anderson_depth.value(), 0);
  EXPECT_FALSE(c.pgd.fixed_point_tolerance.has_value());  // not in the file: the solver's own default
  EXPECT_EQ(drom::offline::pgd_settings(c).fixed_point_tolerance, drom::pgd::PgdSettings{}.fixed_point_tolerance);
  EXPECT_EQ(c.pgd.update_every.value(), 2);
  EXPECT_EQ(c.pgd_penalty, 1e9);
  EXPECT_NE(error_of({"solver.kind=pgd", "mesh.element=hex27", "solver.residual_tolerance=2"}).find("solver.residual_tolerance"), std::string::npos);
}

TEST(CaseFile, StationsPerFactorizationIsAutoByDefaultOrACount) {
  EXPECT_EQ(load_case(std::nullopt, {}).stations_per_factorization, 0);  // "auto"
  EXPECT_EQ(load_case(std::nullopt, {"solver.stations_per_factorization='auto'"}).stations_per_factorization, 0);
  EXPECT_EQ(load_case(std::nullopt, {"solver.stations_per_factorization=8"}).stations_per_factorization, 8);
  EXPECT_NE(error_of({"solver.stations_per_factorization='often'"}).find("solver.stations_per_factorization"), std::string::npos);
  EXPECT_NE(error_of({"solver.stations_per_factorization='often'"}).find("\"auto\""), std::string::npos);
  EXPECT_NE(error_of({"solver.stations_per_factorization=0"}).find("solver.stations_per_factorization"), std::string::npos);
}

TEST(CaseFile, WrongTypesMissingFieldsAndRangesNameTheKeyAndLine) {
  EXPECT_NE(error_of({"mesh.nx=2.5"}).find("--set mesh.nx: expected an integer"), std::string::npos);
  EXPECT_NE(error_of({"part.thickness='thick'"}).find("part.thickness: expected a number"), std::string::npos);
  EXPECT_NE(error_of({"material.poisson_ratio=0.5"}).find("material.poisson_ratio = 0.5: expected a number in (-1, 0.5)"), std::string::npos);
  EXPECT_NE(error_of({"part.shape=sphere"}).find("expected one of \"plate\", \"panel\", \"stl\""), std::string::npos);
  EXPECT_NE(error_of({"pocket.depth=10"}).find("pocket.depth: must be less than part.thickness"), std::string::npos);
  EXPECT_NE(error_of({"pocket.length_x=900"}).find("pocket.length_x: the pocket extends past the part"), std::string::npos);

  const auto negative = write_temp("negative.toml", "name = 'x'\n[part]\nshape = 'plate'\nlength_x = 100.0\nlength_y = 100.0\nthickness = -10.0\n");
  const std::string msg = error_of({}, negative);
  EXPECT_NE(msg.find("negative.toml:6: part.thickness = -10.0: expected a number > 0"), std::string::npos) << msg;

  const auto missing = write_temp("missing.toml", "name = 'x'\n[part]\nshape = 'plate'\nlength_x = 100.0\nlength_y = 100.0\n");
  EXPECT_NE(error_of({}, missing).find("part.thickness: missing"), std::string::npos);
  EXPECT_NE(error_of({"stress.sigma22=[1]"}).find("stress.sigma22: has 1 coefficients"), std::string::npos);
}

TEST(CaseFile, ClampThatMissesTheMeshIsAnError) {
  const auto c = load_case(std::nullopt, {"mesh.nx=4", "mesh.ny=4", "clamps.0.box=[0, 1, 0, 1]"});
  const auto part = drom::offline::build_part(c);
  try {
    drom::offline::clamp_dofs(c, part);
    FAIL() << "expected an InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("clamps.0"), std::string::npos);
  }
}

TEST(CaseFile, MeasuredProfileTableIsFittedToTheBasis) {
  // sigma(depth) sampled from a known even profile: the fit must return its coefficients.
  const double e = 10;
  std::string csv = "depth,sigma11,sigma22\n";
  const drom::fem::StressProfile truth{{2, 4, 6}, {-60, 30, -15}, {-40, 20, -10}};
  for (int i = 0; i <= 40; ++i) {
    const double depth = e * i / 40.0;
    const auto s = truth.evaluate(1 - 2 * depth / e);
    csv += std::to_string(depth) + "," + std::to_string(s[0]) + "," + std::to_string(s[1]) + "\n";
  }
  auto c = load_case(std::nullopt, {"mesh.nx=4", "mesh.ny=4", "clamps.0.box=[0, 300, 0, 300]"});
  c.table = write_temp("profile.csv", csv);
  const auto part = drom::offline::build_part(c);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_NEAR(part.profile.sigma11[k], truth.sigma11[k], 1e-4);
    EXPECT_NEAR(part.profile.sigma22[k], truth.sigma22[k], 1e-4);
  }
  // Both a table and coefficients in one case is ambiguous.
  EXPECT_NE(error_of({"stress.table='profile.csv'"}).find("give either a table or sigma11/sigma22"), std::string::npos);
  // A malformed table names its line.
  c.table = write_temp("bad_profile.csv", "depth,sigma11,sigma22\n0,1,2\n1,abc,3\n");
  try {
    drom::offline::build_part(c);
    FAIL() << "expected an InputError";
  } catch (const InputError& err) {
    EXPECT_NE(std::string(err.what()).find("bad_profile.csv:3: column 2 is not a number"), std::string::npos) << err.what();
  }
}

// Issue 27: what the fuzzer found in --set (fuzz/case_overrides.cpp, docs/robustness.md).
TEST(CaseFile, HostileOverridesAreAClearErrorQuotingTheirBytes) {
  // The finding: a NUL in an override cut the message to "--set cl"; bytes that are not text are now
  // quoted as \xNN.
  const std::string with_nul("cl\0\0\0\xc7\xf5\x92\x9ash.n", 13);
  EXPECT_EQ(error_of({"mesh.ny=18", with_nul}), "--set 'cl\\x00\\x00\\x00\\xc7\\xf5\\x92\\x9ash.n': expected key=value");
  // Found reading the code around it: an array index past stoul's range was an std::out_of_range, not an InputError.
  EXPECT_NE(error_of({"clamps.99999999999999999999.face=top"}).find("--set clamps.99999999999999999999.face: '99999999999999999999' is not a table"),
            std::string::npos)
      << error_of({"clamps.99999999999999999999.face=top"});
}
