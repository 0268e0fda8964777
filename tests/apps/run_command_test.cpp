// drom run and drom study end to end on coarse versions of both reference cases: every output is
// written and readable, and the headline figures match the stored ones (regression, with the
// tolerances below). The stored figures were measured with this resolution on the development
// machine; the loop is deterministic (seeded noise), so only floating-point drift between machines
// is allowed for.
#include "drom_process.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <sstream>

namespace {

std::filesystem::path root() { return std::filesystem::temp_directory_path() / "drom_run_tests"; }

const std::string kFlat =
    " --set mesh.nx=10 --set mesh.ny=10 --set path.station_spacing=300 --set removal.voxel_size=1.0"
    " --set clamps.0.box=[0,100,0,100] --set clamps.1.box=[900,1000,0,100] --set clamps.2.box=[0,100,900,1000] --set clamps.3.box=[900,1000,900,1000]";
const std::string kPanel = std::string(" ") + DROM_SOURCE_DIR + "/cases/curved_panel.toml --set mesh.nx=6 --set mesh.ny=6 --set path.station_spacing=150";

nlohmann::json summary(const std::filesystem::path& dir) { return nlohmann::json::parse(std::ifstream(dir / "summary.json")); }

struct Stored {
  double uncorrected_max, corrected_max_from_3, shape_end;
  int learned_pass;
};

void check_run(const std::string& name, const std::string& args, const Stored& stored) {
  const auto out = root() / name;
  std::filesystem::remove_all(out);
  const DromResult r = run_drom("run" + args + " --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("path error with correction, max from pass 3"), std::string::npos) << r.output;  // the printed table
  const auto s = summary(out);
  const auto& h = s["headline"];
  std::printf("%s: uncorrected max %.5f mm, learned in pass %d, corrected max from pass 3 %.3e mm, final shape at the end %.4f mm (target pass: %.4f)\n", name.c_str(),
              h["path_error_uncorrected_max_mm"].get<double>(), h["learned_during_pass"].get<int>(), h["path_error_corrected_max_from_pass3_mm"].get<double>(),
              h["final_shape_max_error_end_mm"].get<double>(), h["final_shape_max_error_end_of_target_pass_mm"].get<double>());
  // The truth's distortion is physics: tight. What the loop achieves depends on the noise draws and
  // the fit: a factor.
  EXPECT_NEAR(h["path_error_uncorrected_max_mm"].get<double>(), stored.uncorrected_max, 0.02 * stored.uncorrected_max);
  EXPECT_NEAR(h["learned_during_pass"].get<int>(), stored.learned_pass, 1);
  EXPECT_LT(h["path_error_corrected_max_from_pass3_mm"].get<double>(), std::max(1.5 * stored.corrected_max_from_3, stored.corrected_max_from_3 + 5e-4));
  EXPECT_LT(h["final_shape_max_error_end_mm"].get<double>(), std::max(1.5 * stored.shape_end, stored.shape_end + 2e-3));
  // The correction is worth having: well under the distortion it corrects.
  EXPECT_LT(h["path_error_corrected_max_from_pass3_mm"].get<double>(), 0.1 * h["path_error_uncorrected_max_mm"].get<double>());

  for (const char* f : {"passes.csv", "path_samples.csv", "offsets.csv", "corrected_program.nc", "final_shape.pvd", "summary.json"})
    EXPECT_TRUE(std::filesystem::exists(out / f)) << f;
  // passes.csv: one row per pass, and as many as the summary says.
  std::ifstream passes(out / "passes.csv");
  std::string line;
  int rows = -1;
  while (std::getline(passes, line)) ++rows;
  EXPECT_EQ(rows, static_cast<int>(s["corrected"]["passes"].size()));
  // The last final-shape prediction, with its band, readable by VTK.
  vtkNew<vtkXMLUnstructuredGridReader> reader;
  reader->SetFileName((out / ("final_shape_pass_" + std::to_string(rows) + ".vtu")).c_str());
  reader->Update();
  EXPECT_GT(reader->GetOutput()->GetNumberOfCells(), 0);
  for (const char* field : {"predicted_mm", "true_mm", "vertical_error_mm", "vertical_sd_mm", "inside_band95"})
    EXPECT_NE(reader->GetOutput()->GetPointData()->GetArray(field), nullptr) << field;
  // The corrected program: G-code with moves, and Z carrying the compensation somewhere.
  std::ifstream gcode(out / "corrected_program.nc");
  std::stringstream text;
  text << gcode.rdbuf();
  EXPECT_NE(text.str().find("G1 X"), std::string::npos);
  EXPECT_NE(text.str().find("M30"), std::string::npos);
}

}  // namespace

TEST(RunCommand, CoarseFlatPlateMatchesItsStoredFigures) { check_run("flat", kFlat, {0.94560, 6.392e-4, 0.0002, 1}); }

TEST(RunCommand, CoarseCurvedPanelMatchesItsStoredFigures) { check_run("panel", kPanel, {0.03668, 4.977e-4, 0.0023, 1}); }

TEST(StudyCommand, SweepsCalibrationAndReportsItsBias) {
  const auto out = root() / "study";
  std::filesystem::remove_all(out);
  const DromResult r = run_drom("study" + kFlat + " --param calibration --values 0,1 --quiet --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s = summary(out);
  ASSERT_EQ(s["rows"].size(), 2u);
  EXPECT_EQ(s["rows"][0]["calibration"]["rms_bias_mm"].get<double>(), 0.0);  // no error, no bias
  const auto& c = s["rows"][1]["calibration"];
  std::printf("study, 1 mm along the feed: rms bias %.2e mm, rms slope x offset %.2e mm, ratio %.3f\n", c["rms_bias_mm"].get<double>(),
              c["rms_slope_times_offset_mm"].get<double>(), c["ratio"].get<double>());
  EXPECT_NEAR(c["ratio"].get<double>(), 1.0, 0.2);
  EXPECT_TRUE(std::filesystem::exists(out / "study.csv"));
}

TEST(StudyCommand, UnknownParameterOrNoValuesIsAClearError) {
  const auto bad = run_drom("study --param colour --values 1 --out " + (root() / "bad").string());
  EXPECT_EQ(bad.exit_code, 2);
  EXPECT_NE(bad.output.find("--param: expected one of"), std::string::npos) << bad.output;
  const auto bad_case = run_drom("run --set sensor.period=-1 --out " + (root() / "bad").string());
  EXPECT_EQ(bad_case.exit_code, 2);
  EXPECT_NE(bad_case.output.find("sensor.period"), std::string::npos) << bad_case.output;
}
