// drom orient end to end (issue 44, check 3): on the seed's bump the corrected axis asks the rotary
// axes for far more than they give at the programmed feed; the ratios are on the console and in
// summary.json, and the program, read back and judged, is written with a warning naming the slowdown.
// A result beyond a stroke exits 3 with no runnable program.
#include "drom_process.hpp"
#include "tests/machine/shop_safe_program.hpp"
#include "tests/scratch_folder.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

namespace fs = std::filesystem;

namespace {

fs::path root() {
  const fs::path r = drom::tests::scratch_folder("drom_orient_command_");
  fs::create_directories(r);
  return r;
}

const std::string kCases = std::string(DROM_SOURCE_DIR) + "/cases/";

}  // namespace

TEST(OrientCommand, TheBumpsLimitRatiosAreOnTheConsoleAndItsProgramIsJudged) {
  const fs::path out = root() / "bump";
  const DromResult r = run_drom("orient " + kCases + "orient_bump.toml --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  // The rotary axes' demand against their limits (the corrected axis), printed as summary.json has it.
  const auto& ratio = s["machine"]["max_ratio_to_limit_after"];
  EXPECT_GT(ratio["velocity"].get<double>(), 10);
  EXPECT_GT(ratio["acceleration"].get<double>(), 100);
  EXPECT_NE(r.output.find("rotary axes at the programmed feed, demanded over available: velocity "), std::string::npos) << r.output;
  // The posted program's verdict: every axis, read back from the text. Its blocks ask at least the
  // velocity orient estimates from its poses (by central differences, so smoothed over two steps).
  const auto& v = s["program_verdict"];
  EXPECT_TRUE(v["runnable"].get<bool>());
  EXPECT_TRUE(v["slows_down"].get<bool>());
  EXPECT_GE(v["demand_at_programmed_feed"]["velocity"]["ratio"].get<double>(), 0.95 * ratio["velocity"].get<double>());
  EXPECT_EQ(v["demand_at_programmed_feed"]["velocity"]["axis"], "C");
  EXPECT_GT(v["singularity_passages"].get<int>(), 0);
  EXPECT_NE(r.output.find("warning: at its programmed feed the program asks more than the machine's axes give"), std::string::npos) << r.output;
  std::ifstream in(out / "program.ngc");
  shop_safe::expect_shop_safe(std::string(std::istreambuf_iterator<char>(in), {}), "bump program.ngc");
}

TEST(OrientCommand, AResultBeyondAStrokeExitsThreeWithNoProgram) {
  const fs::path out = root() / "corner_off_table";
  const DromResult r = run_drom("orient " + kCases + "orient_corner.toml --set machine.part_origin=[400.0,0.0,0.0] --set check.voxel=1 --quiet --out " + out.string());
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("beyond its stroke [-355, 355] mm"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out / "program.ngc"));
  EXPECT_TRUE(fs::exists(out / "summary.json"));
}
