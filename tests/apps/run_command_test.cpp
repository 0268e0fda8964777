// drom run and drom study end to end on coarse versions of both reference cases: every output is
// written and readable, and the headline figures match the stored ones (regression, with the
// tolerances below). The stored figures were measured with this resolution on the development
// machine; the loop is deterministic (seeded noise), so only floating-point drift between machines
// is allowed for. Issue 29's exact removal moved them (docs/levelset.md, "Regression figures").
#include "run_checks.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <string>

namespace {

const std::string kFlat =
    " --set mesh.nx=10 --set mesh.ny=10 --set path.station_spacing=300 --set removal.voxel_size=1.0"
    " --set clamps.0.box=[0,100,0,100] --set clamps.1.box=[900,1000,0,100] --set clamps.2.box=[0,100,900,1000] --set clamps.3.box=[900,1000,900,1000]";
const std::string kPanel = std::string(" ") + DROM_SOURCE_DIR + "/cases/curved_panel.toml --set mesh.nx=6 --set mesh.ny=6 --set path.station_spacing=150";

}  // namespace

TEST(RunCommand, CoarseFlatPlateMatchesItsStoredFigures) { check_run("flat", kFlat, {0.94621, 7.414e-4, 0.0007, 1}); }

TEST(RunCommand, CoarseCurvedPanelMatchesItsStoredFigures) { check_run("panel", kPanel, {0.03686, 5.366e-4, 0.0034, 1}); }

TEST(StudyCommand, SweepsCalibrationAndReportsItsBias) {
  const auto out = run_test_root() / "study";
  std::filesystem::remove_all(out);
  const DromResult r = run_drom("study" + kFlat + " --param calibration --values 0,1 --quiet --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s = run_summary(out);
  ASSERT_EQ(s["rows"].size(), 2u);
  EXPECT_EQ(s["rows"][0]["calibration"]["rms_bias_mm"].get<double>(), 0.0);  // no error, no bias
  const auto& c = s["rows"][1]["calibration"];
  std::printf("study, 1 mm along the feed: rms bias %.2e mm, rms slope x offset %.2e mm, ratio %.3f\n", c["rms_bias_mm"].get<double>(),
              c["rms_slope_times_offset_mm"].get<double>(), c["ratio"].get<double>());
  EXPECT_NEAR(c["ratio"].get<double>(), 1.0, 0.2);
  EXPECT_TRUE(std::filesystem::exists(out / "study.csv"));
}

TEST(StudyCommand, UnknownParameterOrNoValuesIsAClearError) {
  const auto bad = run_drom("study --param colour --values 1 --out " + (run_test_root() / "bad").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("--param: expected one of"), std::string::npos) << bad.output;
  const auto bad_case = run_drom("run --set sensor.period=-1 --out " + (run_test_root() / "bad").string());
  EXPECT_EQ(bad_case.exit_code, 2);
  EXPECT_NE(bad_case.output.find("sensor.period"), std::string::npos) << bad_case.output;
}
