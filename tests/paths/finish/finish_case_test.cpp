// Finishing cases (issue 22, check 8): bad input gets a clear error naming the file, the line and
// the key: a degenerate patch, a missing STEP file or one without faces, a scallop height out of
// range, an orientation that undercuts the surface; and the shipped cases read.
#include "paths/finish/finish_case.hpp"
#include "support/input_error.hpp"
#include "tests/scratch_folder.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>

namespace {

namespace fs = std::filesystem;

fs::path write_case(const std::string& name, const std::string& text) {
  const fs::path dir = drom::tests::scratch_folder("drom_finish_case_");
  fs::create_directories(dir);
  std::ofstream(dir / name) << text;
  return dir / name;
}

const std::string kRubio =
    "name = \"t\"\n"
    "[surface]\nkind = \"bezier\"\ncount = [3, 3]\npoints = [\n"
    "  [0, -15.32, -12.85], [0, -6.42, 7.66], [0, 15.32, 12.85],\n"
    "  [40, -18.53, -9.02], [40, -9.64, 11.49], [40, 12.10, 16.68],\n"
    "  [80, -28.17, 2.46], [80, -22.49, 26.81], [80, 2.46, 28.17]]\n";

std::string error_of(const std::string& text, const std::vector<std::string>& overrides = {}) {
  const fs::path p = write_case("case.toml", text);
  try {
    drom::paths::load_finish_case(p, overrides);
  } catch (const drom::InputError& e) {
    return e.what();
  }
  return "";
}

TEST(FinishCase, ShippedCasesRead) {
  for (const char* name : {"rubio", "choi", "inclined_plane"}) {
    const auto c = drom::paths::load_finish_case(fs::path(DROM_SOURCE_DIR) / "cases" / (std::string(name) + ".toml"), {});
    EXPECT_EQ(c.name, name);
    EXPECT_DOUBLE_EQ(c.settings.scallop, 0.01);
  }
}

TEST(FinishCase, ScallopOutOfRange) {
  const std::string p = write_case("case.toml", kRubio).string();
  EXPECT_NE(error_of(kRubio + "[finish]\nscallop = 0.0\n").find(p + ":10: finish.scallop = 0.0: expected a number > 0"), std::string::npos)
      << error_of(kRubio + "[finish]\nscallop = 0.0\n");
  const std::string high = error_of(kRubio + "[tool]\nkind = \"torus\"\nradius = 5.0\ncorner_radius = 2.0\n[finish]\nscallop = 2.5\n");
  EXPECT_NE(high.find(p + ":14: finish.scallop: must be below the tool's corner radius (2 mm)"), std::string::npos) << high;
  const std::string ball = error_of(kRubio + "[tool]\nkind = \"ball\"\nradius = 3.0\n[finish]\nscallop = 3.0\n");
  EXPECT_NE(ball.find(":13: finish.scallop: must be below the tool's radius (3 mm)"), std::string::npos) << ball;
}

TEST(FinishCase, UndercutOrientation) {
  // A horizontal tool along +X: Rubio's normals lean towards -X, so it would cut from behind.
  const std::string e = error_of(kRubio + "[finish]\nsetup = \"3+2\"\norientation = [90.0, 0.0]\n");
  EXPECT_NE(e.find(":11: finish.orientation: the tool axis"), std::string::npos) << e;
  EXPECT_NE(e.find("undercuts the surface"), std::string::npos) << e;
  // Upright is fine.
  EXPECT_EQ(error_of(kRubio + "[finish]\norientation = [0.0, 0.0]\n"), "");
}

TEST(FinishCase, DegenerateAndStepErrors) {
  const std::string degenerate = error_of("name = \"t\"\n[surface]\nkind = \"bezier\"\ncount = [2, 2]\npoints = [[0, 0, 0], [0, 0, 0],\n [10, 0, 0], [10, 10, 1]]\n");
  EXPECT_NE(degenerate.find(":5: surface.points: degenerate patch"), std::string::npos) << degenerate;
  const std::string missing = error_of("name = \"t\"\n[surface]\nkind = \"step\"\nstep = \"no_such_part.step\"\nface = 2\n");
  EXPECT_NE(missing.find(":4: surface.step: "), std::string::npos) << missing;
  EXPECT_NE(missing.find("no_such_part.step: no such STEP file"), std::string::npos) << missing;
  const fs::path empty = write_case("empty.step", "ISO-10303-21;\nHEADER;\nFILE_DESCRIPTION((''),'2;1');\nFILE_NAME('','',(''),(''),'','','');\n"
                                                  "FILE_SCHEMA(('AUTOMOTIVE_DESIGN'));\nENDSEC;\nDATA;\nENDSEC;\nEND-ISO-10303-21;\n");
  const std::string faceless = error_of("name = \"t\"\n[surface]\nkind = \"step\"\nstep = \"empty.step\"\n");
  EXPECT_NE(faceless.find(":4: surface.step: "), std::string::npos) << faceless;
  EXPECT_NE(faceless.find("empty.step: the STEP file holds no face"), std::string::npos) << faceless;
  EXPECT_NE(error_of(kRubio + "[finish]\nstepover = \"wide\"\n").find(":10: finish.stepover = \"wide\": expected one of"), std::string::npos);
  EXPECT_NE(error_of(kRubio + "[finish]\nscalop = 0.01\n").find("finish.scalop: unknown key"), std::string::npos);
}

}  // namespace
