// drom copy end to end: a scanned dome on a plinth (ASCII PLY with normals) copied by packets, its
// outputs written; bad clouds and settings refused with exit code 2 naming the file and what is wrong
// (issue 23, check 6).
#include "dome_cloud.hpp"
#include "drom_process.hpp"
#include "tests/machine/shop_safe_program.hpp"
#include "tests/scratch_folder.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;

namespace {

fs::path root() {
  const fs::path r = drom::tests::scratch_folder("drom_copy_command_");
  fs::create_directories(r);
  return r;
}

fs::path write(const std::string& name, const std::string& text) {
  const fs::path p = root() / name;
  std::ofstream(p) << text;
  return p;
}

}  // namespace

TEST(CopyCommand, DomeIsCopiedByPacketsWithItsOutputs) {
  const fs::path cloud = write("dome.ply", dome_ply());
  const fs::path out = root() / "dome";
  fs::remove_all(out);
  const DromResult r = run_drom("copy " + cloud.string() + " --tool ball:6 --machine ucp710_like --set normals.from_file=true --set visibility.theta_step=10" +
                                " --set finishing.step=1 --set finishing.scallop=0.05 --set roughing.depth=5 --set roughing.longitudinal_step=4 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto s = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(s["command"], "copy");
  // A dome the vertical sees whole within the window [0, 85]: a 3-axis job (issue 45's rule).
  EXPECT_EQ(s["grouping"]["packets"].get<int>(), 1);
  EXPECT_NEAR(s["packets"][0]["axis"][2].get<double>(), 1, 1e-12);
  for (const char* f : {"normals.ply", "packets.vtp", "packet_1/finishing.vtp", "packet_1/finishing_cl.csv", "packet_1/finishing.ngc", "packet_1/roughing.ngc"})
    EXPECT_TRUE(fs::exists(out / f)) << f;
  // The rings where a D6 ball touching the dome would cut the stock's base under it (its lowest point
  // 18 cos(polar) - 3 below z = 0, by more than the graze of 0.05 mm: polar beyond 80.57 degrees,
  // the last three rings, 284 points) are machined from no direction. Every other point is covered
  // by the packet, and no path (finishing or roughing) takes the whole tool into the cloud.
  const int points = s["normals"]["points"].get<int>();
  EXPECT_EQ(s["grouping"]["unmachinable"].get<int>(), dome_points_past(80.57));
  EXPECT_EQ(s["grouping"]["covered"].get<int>() + s["grouping"]["reattached"].get<int>(), points - dome_points_past(80.57));
  for (const auto& p : s["packets"]) {
    EXPECT_EQ(p["roughing"]["check"]["positions_over_tolerance"].get<long long>(), 0);
    EXPECT_EQ(p["finishing"]["check"]["positions_over_tolerance"].get<long long>(), 0);
    EXPECT_LE(p["finishing"]["check"]["deepest_mm"].get<double>(), 0.01 + 1e-9);  // the chord tolerance, as the check allows it
    EXPECT_GT(p["finishing"]["cycle_time_s"].get<double>(), 0);
  }
  EXPECT_NE(r.output.find("packets"), std::string::npos);
  // Issue 44, check 2: both programs are ready to run, and were judged before being written.
  for (const char* op : {"finishing", "roughing"}) {
    std::ifstream in(out / "packet_1" / (std::string(op) + ".ngc"));
    shop_safe::expect_shop_safe(std::string(std::istreambuf_iterator<char>(in), {}), std::string("packet_1/") + op + ".ngc");
    EXPECT_TRUE(s["packets"][0][op]["program_verdict"]["runnable"].get<bool>()) << op;
  }
  // The G-code indexes the table once per program and is read back by drom machine.
  const DromResult m = run_drom("machine " + (out / "packet_1" / "finishing.ngc").string() + " --machine ucp710_like --out " + (out / "check").string());
  EXPECT_EQ(m.exit_code, 0) << m.output;
}

// Issue 44, check 5: a scan with "no return" points (NaN) and one stray point 5 m above the part is
// copied as the clean scan is; what was dropped is counted in summary.json and on the console.
TEST(CopyCommand, NanPointsAndAFarOutlierAreDroppedAndCounted) {
  const fs::path cloud = write("dome_dirty.ply", dome_ply({"nan 0 1 0 0 1", "1 nan 1 0 0 1", "0 0 5000 0 0 1", "1 1 1 nan 0 0"}));
  const fs::path out = root() / "dome_dirty";
  const std::string args = "copy " + cloud.string() + " --tool ball:6 --machine ucp710_like --set normals.from_file=true --set visibility.theta_step=10" +
                           " --set finishing.step=1 --set finishing.scallop=0.05 --set roughing.enabled=false --out " + out.string();
  const DromResult r = run_drom(args);
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("3 not finite and 1 far outliers dropped"), std::string::npos) << r.output;
  const auto s = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  const auto& scan = s["scan"];
  const int kept = scan["points_kept"].get<int>();
  EXPECT_EQ(scan["points_read"].get<int>(), kept + 4);
  EXPECT_EQ(scan["dropped_not_finite"].get<int>(), 3);
  EXPECT_EQ(scan["dropped_far_outliers"].get<int>(), 1);
  EXPECT_NE(scan["first_not_finite"].get<std::string>().find("dome_dirty.ply: line "), std::string::npos);
  EXPECT_EQ(s["cloud_points"].get<int>(), kept);
  // As on the clean dome: only the rings over the base are out of reach, and both coverages are reported.
  EXPECT_EQ(s["grouping"]["unmachinable"].get<int>(), dome_points_past(80.57));
  EXPECT_NEAR(scan["coverage_of_points_with_normal"].get<double>(), s["grouping"]["coverage"].get<double>(), 1e-12);
  EXPECT_LE(scan["coverage_of_points_kept"].get<double>(), scan["coverage_of_points_with_normal"].get<double>());
  // cloud.bad_points = "error" names the first bad point instead.
  const DromResult strict = run_drom(args + " --set cloud.bad_points=error");
  EXPECT_EQ(strict.exit_code, 2) << strict.output;
  EXPECT_NE(strict.output.find("dome_dirty.ply: line "), std::string::npos) << strict.output;
  EXPECT_NE(strict.output.find("is not a finite number"), std::string::npos) << strict.output;
}

TEST(CopyCommand, BadCloudsAndSettingsAreRefusedWithExitCode2) {
  const std::string head = "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n";
  const struct {
    std::string name, text, expected, settings;
  } cases[] = {
      {"empty.xyz", "", "the cloud file is empty", ""},
      {"nan.xyz", "0 0 0\n1 nan 0\n", "line 2: column 2: 'nan' is not a finite number", " --set cloud.bad_points=error"},
      {"noz.ply", head + "end_header\n1 2\n3 4\n", "the vertex element has no property 'z'", ""},
      {"long.ply", head + "property float z\nend_header\n1 2 3\n3 4 5\n6 7 8\n", "line 10: data after the 2 vertices the header declares", ""},
  };
  for (const auto& c : cases) {
    const fs::path cloud = write(c.name, c.text);
    const DromResult r = run_drom("copy " + cloud.string() + c.settings + " --quiet --out " + (root() / "bad").string());
    EXPECT_EQ(r.exit_code, 2) << c.name << ": " << r.output;
    EXPECT_NE(r.output.find(c.name), std::string::npos) << r.output;
    EXPECT_NE(r.output.find(c.expected), std::string::npos) << r.output;
  }
  const fs::path dome = write("dome2.ply", dome_ply());
  DromResult r = run_drom("copy " + dome.string() + " --quiet --set packets.coverage=1.5 --out " + (root() / "bad").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("packets.coverage"), std::string::npos) << r.output;
  r = run_drom("copy " + dome.string() + " --quiet --tool cone:6 --out " + (root() / "bad").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  // A cloud without normals asked to use its own.
  const fs::path bare = write("bare.xyz", "0 0 0\n1 0 0\n0 1 0\n");
  r = run_drom("copy " + bare.string() + " --quiet --set normals.from_file=true --out " + (root() / "bad").string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("carries no normals"), std::string::npos) << r.output;
}
