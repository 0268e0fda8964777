// drom machine end to end: a 3-axis program and a 5-axis CL file checked, their outputs written,
// and bad programs or machines refused with exit code 2 and the file, line and key.
#include "drom_process.hpp"
#include "tests/scratch_folder.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <utility>
#include <vector>

namespace fs = std::filesystem;

namespace {

fs::path root() {
  const fs::path r = drom::tests::scratch_folder("drom_machine_command_");
  fs::create_directories(r);
  return r;
}

fs::path write(const std::string& name, const std::string& text) {
  const fs::path p = root() / name;
  std::ofstream(p) << text;
  return p;
}

}  // namespace

TEST(MachineCommand, ThreeAxisProgramWritesItsOutputs) {
  const fs::path program = write("zigzag.ngc", "G21 G90 G64 P0.01\nG0 X0 Y0 Z5\nG1 Z0 F1500\nG1 X100 F3000\nY5\nX0\nY10\nX100\nG2 X100 Y30 I0 J10\nG0 Z5\nM30\n");
  const fs::path out = root() / "zigzag";
  fs::remove_all(out);
  const DromResult r = run_drom("machine " + program.string() + " --machine vmc_3axis --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"feed.csv", "axes.csv", "blocks.csv", "saturation.vtp", "summary.json"}) EXPECT_TRUE(fs::exists(out / f)) << f;
  const auto s = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(s["reader"], "drom");
  EXPECT_GT(s["cycle_time_s"].get<double>(), s["programmed_time_s"].get<double>() * 0.999);
  EXPECT_NEAR(s["cutting_length_mm"].get<double>(), 5 + 100 + 5 + 100 + 5 + 100 + 10 * M_PI, 1e-6);
  EXPECT_GT(s["share_of_cutting_length_at_programmed_feed"].get<double>(), 0.8);
  EXPECT_TRUE(s["travel_violations"].empty());
  EXPECT_NE(r.output.find("cycle time"), std::string::npos);
  // The verdict drom gives its own programs (machine/program_verdict.hpp), here too: X and Y at
  // 3000 mm/min are a tenth of their 30 m/min; a square corner at 50 mm/s stops one axis and starts
  // the other within the ten interpolation cycles the demand is measured over: 50 mm/s / 20 ms =
  // 2.5 m/s² (half of 5 m/s²) by central differences, and its jerk, 2.5 m/s² / 20 ms = 125 m/s³,
  // is 2.5 times the 50 m/s³ limit.
  const auto& demand = s["demand_at_programmed_feed"];
  EXPECT_NEAR(demand["velocity"]["ratio"].get<double>(), 0.1, 1e-9) << demand.dump();
  EXPECT_NEAR(demand["acceleration"]["ratio"].get<double>(), 0.5, 1e-6) << demand.dump();
  EXPECT_NEAR(demand["jerk"]["ratio"].get<double>(), 2.5, 1e-6) << demand.dump();
  EXPECT_TRUE(s["slows_down"].get<bool>());
  EXPECT_NE(r.output.find("demand at the programmed feed jerk"), std::string::npos) << r.output;
}

TEST(MachineCommand, FiveAxisClFileOnTheTableTableMachine) {
  std::string cl = "x,y,z,i,j,k,feed\n";
  char line[160];
  for (int k = 0; k <= 400; ++k) {  // a pass over the saddle z = (x² - y²) / 200, tilted 2° across the feed
    const double x = -40 + 0.2 * k, c = 100, t = 2 * M_PI / 180, n = std::sqrt(1 + x * x / (c * c));
    std::snprintf(line, sizeof line, "%.6f,0,%.6f,%.9f,%.9f,%.9f,%s\n", x, x * x / (2 * c), -x / c / n * std::cos(t), std::sin(t), std::cos(t) / n, k == 0 ? "0" : "3000");
    cl += line;
  }
  const fs::path program = write("saddle.csv", cl), out = root() / "saddle";
  fs::remove_all(out);
  const DromResult r = run_drom("machine " + program.string() + " --machine ucp710_like --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(s["reader"], "cl");
  EXPECT_GT(s["saturated_length_mm"]["C"]["velocity"].get<double>() + s["saturated_length_mm"]["C"]["jerk"].get<double>() +
                s["saturated_length_mm"]["C"]["acceleration"].get<double>(),
            0);
  EXPECT_LT(s["share_of_cutting_length_at_programmed_feed"].get<double>(), 1.0);
  EXPECT_GT(s["cycle_time_over_programmed"].get<double>(), 1.0);
}

TEST(MachineCommand, BadInputExitsWithTwoNamingTheFileLineAndKey) {
  const fs::path far = write("far.ngc", "G21 G90\nG0 X0 Y0 Z5\nG1 X900 F1000\nM30\n");
  DromResult r = run_drom("machine " + far.string() + " --machine vmc_3axis --out " + (root() / "far").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("far.ngc:3: X = 900"), std::string::npos) << r.output;
  EXPECT_TRUE(fs::exists(root() / "far" / "summary.json"));  // the report is still written
  const fs::path rotary = write("rotary.ngc", "G21 G90\nG0 X0 Y0 Z5\nG1 X10 A30 F1000\nM30\n");
  r = run_drom("machine " + rotary.string() + " --machine vmc_3axis --out " + (root() / "rotary").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("rotary.ngc:3"), std::string::npos) << r.output;
  const fs::path machine = write("typo.toml", "name = \"t\"\nkinematics = \"three_axis\"\njunction_tolerence = 0.1\n");
  r = run_drom("machine " + far.string() + " --machine " + machine.string() + " --out " + (root() / "typo").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("typo.toml"), std::string::npos) << r.output;
  r = run_drom("machine " + far.string() + " --machine vmc_3axis --set axes.X.velocity=-1 --out " + (root() / "neg").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("axes.X.velocity"), std::string::npos) << r.output;
  const double tilt = 130 * M_PI / 180;
  char cl[256];
  std::snprintf(cl, sizeof cl, "x,y,z,i,j,k,feed\n0,0,10,0,0,1,0\n5,0,10,0,%.6f,%.6f,1000\n", std::sin(tilt), std::cos(tilt));
  const fs::path unreachable = write("tilt.csv", cl);
  r = run_drom("machine " + unreachable.string() + " --machine ucp710_like --out " + (root() / "tilt").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("tilt.csv:3"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("stroke"), std::string::npos) << r.output;
}

// Issue 44, check 4: a program cut short (no M2/M30, no closing %) is refused naming its last line,
// by drom's reader as by LinuxCNC's; a program with no move at all is reported as such, exit 0.
TEST(MachineCommand, AProgramWithNoEndIsRefusedAndOneWithNoMoveTakesNoTime) {
  const struct {
    std::string name, text, expected;
  } cut_short[] = {
      {"cut.ngc", "G21 G90\nG0 X0 Y0 Z5\nG1 X10 F500\nG1 Y10\n", "cut.ngc:4: the program has no end (no M2 or M30, and no '%' around it)"},
      {"open.ngc", "%\nG21 G90\nG0 X0 Y0 Z5\nG1 X10 F500\n", "open.ngc:4: the file ends with no closing '%'"},
  };
  for (const auto& c : cut_short) {
    const fs::path program = write(c.name, c.text);
    const DromResult r = run_drom("machine " + program.string() + " --reader plain --out " + (root() / "cut").string());
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << r.output;
    const DromResult lcnc = run_drom("machine " + program.string() + " --reader rs274 --out " + (root() / "cut").string());
    if (lcnc.output.find("rs274 is not installed") != std::string::npos) continue;
    EXPECT_EQ(lcnc.exit_code, 2) << lcnc.output;
    EXPECT_NE(lcnc.output.find(c.name + ":4: LinuxCNC's interpreter: File ended with no percent sign"), std::string::npos) << lcnc.output;
  }
  // What follows M30, or the closing %, is not read (as LinuxCNC reads it).
  for (const std::string text : {"G21 G90\nG0 X0 Y0 Z5\nG1 X10 F500\nM30\nG1 Y10 (never read)\n", "%\nG21 G90\nG0 X0 Y0 Z5\nG1 X10 F500\n%\nG1 Y10\n"}) {
    const fs::path program = write("ended.ngc", text);
    const DromResult r = run_drom("machine " + program.string() + " --out " + (root() / "ended").string());
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const auto s = nlohmann::json::parse(std::ifstream(root() / "ended" / "summary.json"));
    EXPECT_NEAR(s["cutting_length_mm"].get<double>(), 10, 1e-9) << text;
  }
  const fs::path still = write("tool_change.ngc", "(a tool change and nothing else)\nG21 G90 G17\nT3 M6\nG43 H3\nM30\n");
  const fs::path sub = write("sub.ngc", "; a subroutine file: no M2, its moves run where it is called\no<sub> sub\nG1 X#1 F100\no<sub> endsub\n");
  const fs::path out = root() / "still";
  for (const auto& [program, reader] : std::vector<std::pair<fs::path, std::string>>{{still, "plain"}, {still, "rs274"}, {sub, "auto"}}) {
    const DromResult r = run_drom("machine " + program.string() + " --reader " + reader + " --out " + out.string());
    if (r.output.find("rs274 is not installed") != std::string::npos) continue;
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_NE(r.output.find("no move"), std::string::npos) << r.output;
    const auto s = nlohmann::json::parse(std::ifstream(out / "summary.json"));
    EXPECT_TRUE(s["no_motion"].get<bool>());
    EXPECT_EQ(s["cycle_time_s"].get<double>(), 0.0);
    EXPECT_EQ(s["blocks"].get<int>(), 0);
  }
}
