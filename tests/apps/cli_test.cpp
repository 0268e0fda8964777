// The drom binary itself: exit codes and messages for bad input, and a small end-to-end run.
#include "drom_process.hpp"

#include <gtest/gtest.h>

#include <vtkCellData.h>
#include <vtkDataArray.h>
#include <vtkNew.h>
#include <vtkSmartPointer.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <nlohmann/json.hpp>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace {

DromResult drom(const std::string& args) { return run_drom(args); }

std::filesystem::path temp_dir() {
  const auto dir = std::filesystem::temp_directory_path() / "drom_cli_tests";
  std::filesystem::create_directories(dir);
  return dir;
}

// A 40 x 30 x 6 box as an ASCII STL; `drop_last` leaves a hole.
std::filesystem::path box_stl(const std::string& name, bool drop_last) {
  const double X = 40, Y = 30, Z = 6;
  const double v[8][3] = {{0, 0, 0}, {X, 0, 0}, {X, Y, 0}, {0, Y, 0}, {0, 0, Z}, {X, 0, Z}, {X, Y, Z}, {0, Y, Z}};
  const int tris[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                           {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  const auto path = temp_dir() / name;
  std::ofstream out(path);
  out << "solid box\n";
  for (int t = 0; t < (drop_last ? 11 : 12); ++t) {
    out << " facet normal 0 0 0\n  outer loop\n";
    for (int k = 0; k < 3; ++k) out << "   vertex " << v[tris[t][k]][0] << " " << v[tris[t][k]][1] << " " << v[tris[t][k]][2] << "\n";
    out << "  endloop\n endfacet\n";
  }
  out << "endsolid box\n";
  return path;
}

std::filesystem::path stl_case(const std::filesystem::path& stl) {
  const auto path = temp_dir() / (stl.stem().string() + ".toml");
  std::ofstream(path) << "name = 'box'\n[part]\nshape = 'stl'\nstl = '" << stl.string()
                      << "'\n[material]\nyoung_modulus = 71700.0\npoisson_ratio = 0.33\n[mesh]\ntet_max_volume = 20.0\n"
                         "[stress]\nparity = 'even'\nmax_degree = 4\nsigma11 = [-50.0, 20.0]\nsigma22 = [-50.0, 20.0]\n"
                         "[pocket]\nx_min = 5.0\ny_min = 5.0\nlength_x = 30.0\nlength_y = 20.0\ndepth = 1.5\n"
                         "[tool]\nkind = 'flat'\nradius = 3.0\n[path]\nstepover = 4.0\nstation_spacing = 10.0\n"
                         "[removal]\nvoxel_size = 0.2\nframes = 3\n"
                         "[[clamps]]\nface = 'bottom'\n";
  return path;
}

}  // namespace

TEST(Cli, UnknownKeyExitsWithTwoAndNamesIt) {
  const auto r = drom("check --set mesh.nxx=3");
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("mesh.nxx: unknown key"), std::string::npos) << r.output;
}

TEST(Cli, NegativeThicknessExitsWithTwoAndNamesTheLine) {
  const auto path = temp_dir() / "negative.toml";
  std::ofstream(path) << "name = 'x'\n[part]\nshape = 'plate'\nlength_x = 100.0\nlength_y = 100.0\nthickness = -10.0\n";
  const auto r = drom("run " + path.string() + " --out " + (temp_dir() / "neg_out").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("negative.toml:6: part.thickness = -10.0: expected a number > 0"), std::string::npos) << r.output;
}

TEST(Cli, OpenStlExitsWithTwo) {
  const auto r = drom("mesh " + stl_case(box_stl("open_box.stl", true)).string() + " --out " + (temp_dir() / "open_out").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("open_box.stl: surface is not closed"), std::string::npos) << r.output;
}

TEST(Cli, ClosedStlIsMeshedWithTets) {
  const auto out = temp_dir() / "closed_out";
  const auto r = drom("mesh " + stl_case(box_stl("closed_box.stl", false)).string() + " --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_EQ(summary["element"], "tet10");
  EXPECT_GT(summary["elements"].get<int>(), 50);
  EXPECT_TRUE(std::filesystem::exists(out / "mesh.vtu"));
}

TEST(Cli, UsageErrorsExitWithTwo) {
  EXPECT_EQ(drom("").exit_code, 2);
  EXPECT_EQ(drom("run --no-such-flag").exit_code, 2);
  EXPECT_EQ(drom("run /no/such/case.toml").exit_code, 2);
  EXPECT_EQ(drom("--help").exit_code, 0);
}

// Issue 44: each subcommand has its own default output folder, as its --help says (one shared
// option variable once sent every subcommand to the last one registered, out/machine).
TEST(Cli, EachSubcommandWritesToItsOwnDefaultFolder) {
  const std::pair<const char*, const char*> defaults[] = {{"run", "out"},           {"offline", "out/offline"}, {"truth", "out/truth"}, {"reduce", "out/model"},
                                                          {"finish", "out/finish"}, {"copy", "out/copy"},       {"orient", "out/orient"}, {"machine", "out/machine"},
                                                          {"mesh", "out/mesh"},     {"removal", "out/removal"}, {"study", "out/study"}};
  for (const auto& [command, folder] : defaults) {
    const auto help = drom(std::string(command) + " --help").output;
    EXPECT_NE(help.find(std::string("--out TEXT=") + folder + " "), std::string::npos) << command << ":\n" << help;
  }
  // What a run without --out really writes: drom machine and drom mesh from an empty folder.
  const auto here = std::filesystem::current_path();
  const auto dir = temp_dir() / "defaults";
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  std::ofstream(dir / "p.ngc") << "G21 G90\nG0 X0 Y0 Z5\nG1 X10 F500\nM30\n";
  std::filesystem::current_path(dir);
  const auto machine = drom("machine p.ngc --quiet");
  const auto mesh = drom("mesh --set mesh.nx=10 --set mesh.ny=10 --quiet");
  std::filesystem::current_path(here);
  EXPECT_EQ(machine.exit_code, 0) << machine.output;
  EXPECT_EQ(mesh.exit_code, 0) << mesh.output;
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "machine" / "summary.json"));
  EXPECT_TRUE(std::filesystem::exists(dir / "out" / "mesh" / "mesh.vtu"));
  EXPECT_FALSE(std::filesystem::exists(dir / "out" / "machine" / "mesh.vtu"));
}

TEST(Cli, RunWritesVtkAndSummaryOnACoarsePlate) {
  const auto out = temp_dir() / "run_out";
  std::filesystem::remove_all(out);
  const auto r = drom("layer --set mesh.nx=10 --set mesh.ny=10 --set clamps.0.box=[0,100,0,100] --set clamps.1.box=[900,1000,0,100] "
                      "--set clamps.2.box=[0,100,900,1000] --set clamps.3.box=[900,1000,900,1000] --quiet --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"layer.pvd", "layer_0_intact.vtu", "layer_1_thinned_clamped.vtu", "layer_2_thinned_free.vtu", "summary.json"})
    EXPECT_TRUE(std::filesystem::exists(out / f)) << f;
  const auto s = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  EXPECT_LT(s["intact_clamped_max_displacement_mm"].get<double>(), 1e-9);
  EXPECT_LT(s["free_plate_curvature_per_mm"]["relative_error"].get<double>(), 0.01);
  EXPECT_GT(s["thinned_clamped_max_vertical_displacement_mm"].get<double>(), 0.1);
  // Each file shows its own state: the intact stock is whole, the thinned one has lost cells.
  auto read = [&](const char* name) {
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    reader->SetFileName((out / name).c_str());
    reader->Update();
    vtkSmartPointer<vtkUnstructuredGrid> grid = reader->GetOutput();
    return grid;
  };
  const auto intact = read("layer_0_intact.vtu"), thinned = read("layer_1_thinned_clamped.vtu");
  double range[2];
  intact->GetCellData()->GetArray("activity")->GetRange(range);
  EXPECT_EQ(range[0], 1.0);
  EXPECT_EQ(intact->GetNumberOfCells(), 10 * 10 * 5);
  EXPECT_LT(thinned->GetNumberOfCells(), intact->GetNumberOfCells());
}

TEST(Cli, RemovalOnAnStlPartWritesItsOutputs) {
  const auto out = temp_dir() / "removal_out";
  std::filesystem::remove_all(out);
  const auto r = drom("removal " + stl_case(box_stl("removal_box.stl", false)).string() + " --quiet --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* f : {"removal.h5", "volumes.csv", "removal.pvd", "removed_surface.vtp", "toolpath.nc", "summary.json"})
    EXPECT_TRUE(std::filesystem::exists(out / f)) << f;
  const auto s = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  // Pocket 30 x 20 x 1.5 with a 3 mm flat end mill: the 4 corners keep (1 - pi/4) r^2 each.
  const double exact = 30.0 * 20 * 1.5 - 4 * (1 - M_PI / 4) * 9 * 1.5;
  EXPECT_NEAR(s["removed_volume_mm3"].get<double>() / exact, 1.0, 0.01);
  EXPECT_NEAR(s["mesh_removed_volume_mm3"].get<double>() / exact, 1.0, 0.05);  // tets, not aligned with the floor
  EXPECT_GT(s["stations"].get<int>(), 10);
  // The G-code it wrote drives the same removal when a case names it instead of generating a path.
  std::string text;
  {
    std::ifstream in(stl_case(box_stl("removal_box.stl", false)));
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
  }
  const auto conflict = drom("check " + stl_case(box_stl("removal_box.stl", false)).string() + " --set path.gcode='x.nc'");
  EXPECT_EQ(conflict.exit_code, 2);
  EXPECT_NE(conflict.output.find("path.stepover: describes a generated toolpath"), std::string::npos) << conflict.output;
  text.replace(text.find("stepover = 4.0"), 14, "gcode = '" + (out / "toolpath.nc").string() + "'");
  const auto gcode_case = temp_dir() / "removal_gcode.toml";
  std::ofstream(gcode_case) << text;
  const auto out2 = temp_dir() / "removal_gcode_out";
  const auto again = drom("removal " + gcode_case.string() + " --quiet --out " + out2.string());
  ASSERT_EQ(again.exit_code, 0) << again.output;
  const auto s2 = nlohmann::json::parse(std::ifstream(out2 / "summary.json"));
  EXPECT_NEAR(s2["removed_volume_mm3"].get<double>(), s["removed_volume_mm3"].get<double>(), 1e-3 * exact);
}
