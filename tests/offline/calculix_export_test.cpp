// Issue 28: one station of each coarse case exported with drom offline --export-ccx and solved by
// CalculiX (ccx 2.20, Debian's calculix-ccx): an FE code written by others gives drom's displacement.
// ccx integrates the initial stress with 3 Gauss points a direction, exact for a profile of degree 3
// through an element: there the two must agree to ccx's printed digits (7 significant), partly
// machined elements included; the cases' own profiles (degrees 6 and 7) differ by ccx's quadrature.
#include "offline/calculix_export.hpp"
#include "support/input_error.hpp"

#include "drom_process.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

namespace {

std::filesystem::path dir(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() / "drom_calculix_tests" / name;
  std::filesystem::remove_all(d);
  return d;
}

const std::vector<std::string> kPlate = {"mesh.nx=10", "mesh.ny=10", "path.station_spacing=300", "removal.voxel_size=1.0", "clamps.0.box=[0,100,0,100]",
                                         "clamps.1.box=[900,1000,0,100]", "clamps.2.box=[0,100,900,1000]", "clamps.3.box=[900,1000,900,1000]"};
const std::vector<std::string> kPanel = {"mesh.nx=12", "mesh.ny=12", "path.station_spacing=150", "removal.voxel_size=0.5"};

std::vector<std::string> with(std::vector<std::string> a, const std::vector<std::string>& b) {
  a.insert(a.end(), b.begin(), b.end());
  return a;
}

// max |u_ccx - u_drom| / max |u_drom| for the station, and the export's figures.
struct Compared {
  double relative_difference;
  drom::offline::CalculixExport exported;
};

Compared compare(const std::string& case_file, const std::vector<std::string>& overrides, std::size_t station, const std::string& name) {
  const auto c = drom::case_file::load_case(std::string(DROM_SOURCE_DIR) + "/cases/" + case_file, overrides);
  const auto out = dir(name);
  auto exported = drom::offline::export_calculix_station(c, drom::offline::JobKind::Offline, station, out);
  const auto ccx = drom::fem::run_calculix(exported.deck, exported.deck_stats.nodes);
  const double difference = (ccx.displacement - exported.drom_displacement).cwiseAbs().maxCoeff() / exported.drom_displacement.cwiseAbs().maxCoeff();
  return {difference, std::move(exported)};
}

}  // namespace

TEST(CalculixExport, CcxGivesDromsStationOnACubicProfile) {
  const std::vector<std::string> cubic = {"stress.parity=all", "stress.max_degree=3", "stress.sigma11=[-60,20]", "stress.sigma22=[-40,10]"};
  const auto plate = compare("flat_plate.toml", with(kPlate, cubic), 10, "plate_cubic");
  EXPECT_GT(plate.exported.deck_stats.removed, 0);
  EXPECT_GT(plate.exported.deck_stats.partial, 0);
  EXPECT_GT(plate.exported.drom_displacement.cwiseAbs().maxCoeff(), 0.1);  // mm: a real distortion
  // Measured 1.6e-7: ccx prints 7 significant digits.
  EXPECT_LT(plate.relative_difference, 1e-6);
  const auto panel = compare("curved_panel.toml", with(kPanel, {"stress.max_degree=3", "stress.sigma11=[40]", "stress.sigma22=[15]"}), 20, "panel_cubic");
  EXPECT_GT(panel.exported.deck_stats.partial, 0);
  EXPECT_LT(panel.relative_difference, 1e-6);  // measured 8.3e-8, on curved elements
}

TEST(CalculixExport, CcxUnderIntegratesTheCasesOwnProfiles) {
  // The flat plate's degree-6 profile over 5 element layers: ccx's 3-point rule is off by 5.9e-5
  // (measured); drom's rule is exact for the profile's degree.
  const auto plate = compare("flat_plate.toml", kPlate, 10, "plate_own");
  EXPECT_LT(plate.relative_difference, 2e-4);
  EXPECT_GT(plate.relative_difference, 1e-5);
}

TEST(CalculixExport, WritesTheDeckDromsAnswerAndSummary) {
  const auto out = dir("cli");
  std::string args = "offline " + std::string(DROM_SOURCE_DIR) + "/cases/flat_plate.toml";
  for (const auto& o : kPlate) args += " --set " + o;
  const DromResult r = run_drom(args + " --export-ccx 3 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("ccx -i station_3"), std::string::npos) << r.output;
  ASSERT_TRUE(std::filesystem::exists(out / "station_3.inp"));
  ASSERT_TRUE(std::filesystem::exists(out / "station_3_drom.csv"));
  std::ifstream in(out / "summary.json");
  const auto s = nlohmann::json::parse(in);
  EXPECT_EQ(s["command"], "offline --export-ccx");
  EXPECT_EQ(s["station"], 3);
  EXPECT_EQ(s["stations"], 68);
  EXPECT_EQ(s["unknowns"], 3 * s["nodes"].get<int>());

  // Bad requests: a station past the last, options that belong to the job, a mesh ccx cannot hold.
  const DromResult past = run_drom(args + " --export-ccx 68 --out " + out.string());
  EXPECT_EQ(past.exit_code, 2);
  EXPECT_NE(past.output.find("--export-ccx 68: the case has stations 0..67"), std::string::npos) << past.output;
  const DromResult resume = run_drom(args + " --export-ccx 3 --resume --out " + out.string());
  EXPECT_EQ(resume.exit_code, 2);
  EXPECT_NE(resume.output.find("does not combine with --resume"), std::string::npos) << resume.output;
  const DromResult hex27 = run_drom(args + " --set mesh.element=hex27 --export-ccx 3 --out " + out.string());
  EXPECT_EQ(hex27.exit_code, 2);
  EXPECT_NE(hex27.output.find("Hex20 (C3D20) only"), std::string::npos) << hex27.output;
}
