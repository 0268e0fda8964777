// Issue 24's checks 4 (the voxel field against the direct sum), 5 (the clearance check proves the
// result collision-free, and finds the collisions of the programmed axis) and 7 (bad input).
#include "paths/cutter/tool_assembly.hpp"
#include "paths/orient/force_voxel_field.hpp"
#include "paths/orient/orient_run.hpp"
#include "support/input_error.hpp"

#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <numbers>

namespace drom::paths {
namespace {

// §4-2.3.1: the relative error of |F| (4.5) along a line through the vein, 6 mm from blade 0's
// suction side at mid-height, for voxels of 2, 1 and 0.5 mm: trilinear (4.4), and the higher-order
// samplers (the better of triquadratic and tricubic at each size).
TEST(OrientVoxelField, ErrorAlongTheVein) {
  ImpellerOptions io;
  const KhatibParameters k;
  // One blade side's obstacles keep the precomputation small; the error is local to each voxel anyway.
  io.veins = 0;
  const OrientScene blades = impeller_scene(io);
  const CheckPatch& side = blades.check_patches.at(1);  // blade 0, suction side, outward towards the vein
  ASSERT_EQ(side.name, "blade 0 suction");
  const ObstacleCloud obstacles = ObstacleCloud::from_patch(side.surface, 2, side.flip, k.influence_radius);
  std::vector<Eigen::Vector3d> line;
  for (int i = 0; i <= 200; ++i) {
    const double u = 0.2 + 0.6 * i / 200.0;
    const double r = io.hub_inlet_radius + (io.hub_outlet_radius - io.hub_inlet_radius) * u;
    const double h = io.blade_height_inlet + (io.blade_height_outlet - io.blade_height_inlet) * u;
    const double theta = io.wrap * u + 0.5 * h * std::tan(io.lean) / r + (0.5 * io.thickness + 6) / r;
    line.emplace_back(r * std::cos(theta), r * std::sin(theta), io.hub_inlet_height * (1 - u) * (1 - u) + 0.5 * h);
  }
  auto mean_error = [&](double voxel, VoxelInterpolation interp) {
    const VoxelField field(obstacles, k, {voxel, interp, true, 0});  // the seed's grid alone
    double sum = 0;
    int n = 0;
    for (const auto& p : line) {
      const double exact = repulsive_force(obstacles, p, k, Aggregation::F1).force.norm();
      if (exact <= 0) continue;
      sum += std::abs(field.sample(p).force.norm() - exact) / exact;
      ++n;
    }
    EXPECT_GT(n, 150);
    return sum / n;
  };
  const double e2 = mean_error(2, VoxelInterpolation::trilinear), e1 = mean_error(1, VoxelInterpolation::trilinear);
  const double e05 = mean_error(0.5, VoxelInterpolation::trilinear);
  const double c2 = mean_error(2, VoxelInterpolation::tricubic), c05 = mean_error(0.5, VoxelInterpolation::tricubic);
  const double q2 = mean_error(2, VoxelInterpolation::triquadratic), q05 = mean_error(0.5, VoxelInterpolation::triquadratic);
  RecordProperty("trilinear_2mm", std::to_string(e2));
  std::cout << "trilinear: 2 mm " << e2 * 100 << " %, 1 mm " << e1 * 100 << " %, 0.5 mm " << e05 * 100 << " %; tricubic: 2 mm " << c2 * 100
            << " %, 0.5 mm " << c05 * 100 << " %; triquadratic 2 mm " << q2 * 100 << " %, 0.5 mm " << q05 * 100 << " %\n";
  // The seed's line lies somewhere "along the vein" (its distance to the walls is not given); 6 mm from
  // a blade ours sits nearer the wall than the seed's 6 % suggests.
  EXPECT_GT(e2, 0.03) << "seed: about 6 % at 2 mm";
  EXPECT_LT(e2, 0.15) << "seed: about 6 % at 2 mm";
  EXPECT_NEAR(e05, 0.005, 0.004) << "seed: about 0.5 % at 0.5 mm";
  EXPECT_GT(e2 / e05, 6.0) << "second order: about 16x from 2 to 0.5 mm";
  EXPECT_LT(e1, e2);
  EXPECT_LT(std::min(c2, q2), e2 / 4) << "seed: the cubic sampler about 10x lower";
  EXPECT_LT(std::min(c05, q05), e05 / 8);
}

// Beyond the seed: near a wall the grid cannot follow the 1/r³ force (a corner 0.05 mm from an
// obstacle holds 10⁶ N, spread over its voxel by interpolation); within near_field voxels the exact
// sum takes over, blended out over the band's outer half. Along a line 1 mm from blade 0's suction
// side, 1 mm voxels: the grid alone is off by tens of percent, the near-field-corrected field is exact.
TEST(OrientVoxelField, TheNearFieldIsExactWhereTheGridCannotFollow) {
  ImpellerOptions io;
  const KhatibParameters k;
  io.veins = 0;
  const OrientScene blades = impeller_scene(io);
  const CheckPatch& side = blades.check_patches.at(1);
  ASSERT_EQ(side.name, "blade 0 suction");
  const ObstacleCloud obstacles = ObstacleCloud::from_patch(side.surface, 2, side.flip, k.influence_radius);
  const auto error_at = [&](double gap, double near_field) {
    const VoxelField field(obstacles, k, {1.0, VoxelInterpolation::trilinear, true, near_field});
    double sum = 0, worst = 0;
    int n = 0;
    for (int i = 0; i <= 200; ++i) {
      const double u = 0.2 + 0.6 * i / 200.0;
      const double r = io.hub_inlet_radius + (io.hub_outlet_radius - io.hub_inlet_radius) * u;
      const double h = io.blade_height_inlet + (io.blade_height_outlet - io.blade_height_inlet) * u;
      const double theta = io.wrap * u + 0.5 * h * std::tan(io.lean) / r + (0.5 * io.thickness + gap) / r;
      const Eigen::Vector3d p(r * std::cos(theta), r * std::sin(theta), io.hub_inlet_height * (1 - u) * (1 - u) + 0.5 * h);
      const double exact = repulsive_force(obstacles, p, k, Aggregation::F1).force.norm();
      if (exact <= 0) continue;
      const double e = std::abs(field.force(p).norm() - exact) / exact;
      sum += e;
      worst = std::max(worst, e);
      ++n;
    }
    EXPECT_GT(n, 150);
    return std::pair{sum / n, worst};
  };
  const auto [grid_mean, grid_worst] = error_at(1, 0);
  const auto [near_mean, near_worst] = error_at(1, 3);
  const auto [far_grid, far_grid_worst] = error_at(6, 0);
  const auto [far_near, far_near_worst] = error_at(6, 3);
  std::cout << "1 mm from the blade: grid alone " << grid_mean * 100 << " % (worst " << grid_worst * 100 << " %), near field " << near_mean * 100 << " % (worst "
            << near_worst * 100 << " %); 6 mm: " << far_grid * 100 << " % and " << far_near * 100 << " %\n";
  EXPECT_GT(grid_mean, 0.10) << "the grid alone near the wall";
  EXPECT_LT(near_mean, 0.02) << "the exact sum within 1.5 voxels, blended to 3";
  EXPECT_NEAR(far_near, far_grid, 1e-6) << "6 mm from the wall is past the near field: the grid's own values";
  (void)far_grid_worst;
  (void)far_near_worst;
}

OrientCase small_case(const std::string& scene, const std::vector<std::string>& extra = {}) {
  std::vector<std::string> o = extra;
  return parse_orient_case("[scene]\nkind = \"" + scene + "\"\n", "<test " + scene + ">", o);
}

OrientResult expect_proved(const OrientCase& on, const std::string& scene) {
  OrientResult r = run_orient(on, {"", true, false});
  EXPECT_TRUE(r.after.collisions.empty()) << scene << ": " << r.after.collisions.size() << " violations, worst " << r.after.worst_clearance << " mm";
  EXPECT_GT(r.after.worst_clearance, 0) << scene;
  EXPECT_FALSE(r.before.collisions.empty()) << scene << ": the programmed axis should collide (worst " << r.before.worst_clearance << " mm)";
  EXPECT_LT(r.before.worst_clearance, 0) << scene;
  EXPECT_LT(r.after.worst_gouge, 0.01) << scene;
  std::cout << scene << ": worst clearance " << r.after.worst_clearance << " mm with the model, " << r.before.worst_clearance << " mm without ("
            << r.before.collisions.size() << " poses in collision)\n";
  return r;
}

void expect_proved(const std::string& scene, const std::vector<std::string>& overrides) { (void)expect_proved(small_case(scene, overrides), scene); }

TEST(OrientClearance, BumpIsCollisionFreeWithTheModelOnly) { expect_proved("bump", {}); }
TEST(OrientClearance, CornerIsCollisionFreeWithTheModelOnly) { expect_proved("corner", {}); }
TEST(OrientClearance, ImpellerVeinIsCollisionFreeWithTheModelOnly) {
  expect_proved("impeller", {"scene.veins=1", "scene.v_first=0.2", "scene.v_last=0.8", "scene.v_step=0.2", "check.voxel=1"});
}

// Passes run in parallel, each from its own settled start: one thread or two give the same result.
TEST(OrientClearance, OneThreadOrTwoGiveTheSameResult) {
  const OrientCase c = small_case("impeller", {"scene.veins=1", "scene.v_first=0.2", "scene.v_last=0.8", "scene.v_step=0.2", "check.voxel=1"});
  const OrientResult one = run_orient(c, {"", true, false, 1}), two = run_orient(c, {"", true, false, 2});
  ASSERT_EQ(one.passes.size(), two.passes.size());
  for (std::size_t p = 0; p < one.passes.size(); ++p) {
    ASSERT_EQ(one.passes[p].samples.size(), two.passes[p].samples.size());
    for (std::size_t i = 0; i < one.passes[p].samples.size(); ++i) EXPECT_EQ(one.passes[p].samples[i].axis, two.passes[p].samples[i].axis) << p << " " << i;
  }
  EXPECT_EQ(one.after.worst_clearance, two.after.worst_clearance);
}

// STL check surfaces and the torus cutter, on the corner: a clamp 10 mm beside the second leg, on the
// side the tool now leans to (θf,prog = +0.3), given once as a patch and once as the STL of the same
// quad. Both are repulsive and both are checked: the programmed axis runs into the clamp alike, the
// model keeps clear of it alike.
TEST(OrientClearance, AnStlClampActsAndIsCheckedLikeThePatchItMeshes) {
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / ("drom_orient_stl_" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  {
    // Outward (+x) by the winding, as a CAD export writes it.
    std::ofstream stl(dir / "clamp.stl");
    stl << "solid clamp\n"
        << "facet normal 1 0 0\nouter loop\nvertex 50 -70 -2\nvertex 50 -20 -2\nvertex 50 -20 24\nendloop\nendfacet\n"
        << "facet normal 1 0 0\nouter loop\nvertex 50 -70 -2\nvertex 50 -20 24\nvertex 50 -70 24\nendloop\nendfacet\n"
        << "endsolid clamp\n";
  }
  const std::string scene = "[scene]\nkind = \"corner\"\nroll = 0.3\n";
  const std::string patch = "[[check_surfaces]]\nkind = \"bezier\"\ncount = [2, 2]\npoints = [[50.0, -70.0, -2.0], [50.0, -70.0, 24.0], [50.0, -20.0, -2.0], [50.0, -20.0, 24.0]]\n";
  const std::string mesh = "[[check_surfaces]]\nstl = \"" + (dir / "clamp.stl").string() + "\"\n";
  const OrientResult with_patch = run_orient(parse_orient_case(scene + patch, "<corner + patch clamp>", {}), {"", true, false});
  const OrientResult with_stl = run_orient(parse_orient_case(scene + mesh, "<corner + STL clamp>", {}), {"", true, false});
  const OrientResult without = run_orient(parse_orient_case(scene, "<corner>", {}), {"", true, false});
  std::filesystem::remove_all(dir);
  std::cout << "clamp as a patch: worst " << with_patch.after.worst_clearance << " mm, programmed " << with_patch.before.worst_clearance << " mm ("
            << with_patch.before.collisions.size() << " poses); as STL: " << with_stl.after.worst_clearance << " mm, programmed " << with_stl.before.worst_clearance
            << " mm (" << with_stl.before.collisions.size() << "); no clamp: programmed " << without.before.worst_clearance << " mm ("
            << without.before.collisions.size() << ")\n";
  for (const OrientResult* r : {&with_patch, &with_stl}) {
    EXPECT_TRUE(r->after.collisions.empty()) << r->after.worst_clearance;
    EXPECT_GT(r->after.worst_clearance, 0);
    EXPECT_GT(r->before.collisions.size(), without.before.collisions.size() + 50) << "the programmed axis runs into the clamp";
  }
  EXPECT_NEAR(with_stl.before.worst_clearance, with_patch.before.worst_clearance, 0.05) << "the same quad, checked alike";
  EXPECT_NEAR(static_cast<double>(with_stl.before.collisions.size()), static_cast<double>(with_patch.before.collisions.size()), 3);
  EXPECT_NEAR(with_stl.after.worst_clearance, with_patch.after.worst_clearance, 0.5) << "sampled differently (barycentric vs iso nodes), repelled alike";
}

// The torus (the seed's R5 r2) on an impeller vein, its 10° lead kept: the tool pivots about the tube's
// centre over the contact point, so tilting it does not dip its corner into the hub (the gouge check).
TEST(OrientClearance, ImpellerVeinWithATorusCutterIsCollisionFreeWithTheModelOnly) {
  expect_proved("impeller", {"scene.veins=1", "scene.v_first=0.2", "scene.v_last=0.8", "scene.v_step=0.2", "check.voxel=1", "tool.kind=torus",
                             "tool.radius=5", "tool.corner_radius=2"});
}

// The curved panel of the distortion cases, mounted centred on the C table (its 450 mm would leave the
// UCP 710's Y stroke from its corner): the holder meets the clamp jaws without the model.
// The shipped case (voxel field at 1 mm), every third pass (the first beside the pocket wall y = 75).
TEST(OrientClearance, PanelIsCollisionFreeWithTheModelOnly) {
  const OrientCase c = load_orient_case(std::filesystem::path(DROM_SOURCE_DIR) / "cases" / "orient_panel.toml", {"scene.stepover=135", "check.voxel=1"});
  const OrientResult r = expect_proved(c, "panel");
  // Each pass starts with the holder in a clamp jaw: released from the nearest free axis (free_start).
  EXPECT_EQ(r.summary["model"]["starts_moved_clear"].get<int>(), 3);
}

TEST(OrientBadInput, ClearErrors) {
  // A check surface through the CL path.
  const std::string crossing = R"([scene]
kind = "corner"
[[check_surfaces]]
kind = "bezier"
count = [2, 2]
points = [[30.0, -20.0, -5.0], [30.0, -20.0, 30.0], [30.0, 20.0, -5.0], [30.0, 20.0, 30.0]]
)";
  try {
    run_orient(parse_orient_case(crossing, "crossing.toml"), {"", true, false});
    ADD_FAILURE() << "a check surface across the path was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("crosses the CL path"), std::string::npos) << e.what();
  }
  // A tool longer than the machine's Z stroke.
  try {
    run_orient(small_case("corner", {"tool.stick_out=300", "tool.holder_z=[0.0, 300.0]", "tool.holder_radius=[8.0, 8.0]"}), {"", true, false});
    ADD_FAILURE() << "a 600 mm tool was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("longer than the Z stroke"), std::string::npos) << e.what();
  }
  // k <= 0.
  for (const char* k : {"model.k=0", "model.k=-5"}) {
    try {
      small_case("corner", {k});
      ADD_FAILURE() << k << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("model.k"), std::string::npos) << e.what();
    }
  }
  EXPECT_THROW(small_case("corner", {"model.unknown=1"}), InputError);
}


// A hostile case cannot ask for a scene no machine holds: each size is counted before anything is
// built, and the error names the key (docs/robustness.md, finding 25).
TEST(OrientBadInput, OversizedScenesAreRefusedBeforeTheyAreBuilt) {
  const struct {
    const char* scene;
    std::vector<std::string> overrides;
    const char* key;
  } cases[] = {
      {"impeller", {"scene.v_step=1e-300"}, "scene.v_step"},
      {"impeller", {"scene.v_step=1e-5"}, "scene.v_step"},
      {"impeller", {"scene.point_spacing=1e-250"}, "scene.point_spacing"},
      {"impeller", {"scene.point_spacing=1e-4"}, "scene.point_spacing"},
      {"panel", {"scene.stepover=1e-9"}, "scene.stepover"},
      {"corner", {"tool.nodes=0", "tool.skin_spacing=1e-200"}, "tool.skin_spacing"},
      {"corner", {"tool.nodes=0", "tool.skin_spacing=0.001"}, "tool.skin_spacing"},
  };
  for (const auto& c : cases) {
    try {
      small_case(c.scene, c.overrides);
      ADD_FAILURE() << c.overrides.back() << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.key), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("at most"), std::string::npos) << e.what();
    }
  }
  // Meshes and grids are counted when the scene is built, before they are allocated.
  const struct {
    std::vector<std::string> overrides;
    const char* key;
  } built[] = {
      {{"model.obstacle_spacing=1e-6"}, "model.obstacle_spacing"},
      {{"field.kind=\"voxel\"", "field.voxel=1e-3"}, "field.voxel"},
      {{"check.voxel=1e-3"}, "check.voxel"},
  };
  for (const auto& c : built) {
    const OrientCase oc = small_case("impeller", c.overrides);
    try {
      build_orient_scene(oc);
      ADD_FAILURE() << c.overrides.back() << " was accepted";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find(c.key), std::string::npos) << e.what();
    }
  }
  // The shipped sizes pass: the full impeller is 427 passes.
  const OrientScene full = build_orient_scene(small_case("impeller"));
  EXPECT_EQ(full.passes.size(), 427u);
}

// A result the machine cannot reach (here the corner mounted 400 mm off the table's centre, past the
// UCP 710's X stroke) is reported with the rest of the result, not thrown away: no G-code, the other
// files written, the verdict and the poses in summary.json.
TEST(OrientMachine, PosesOutOfReachAreReportedAndTheRestIsWritten) {
  const std::filesystem::path out = std::filesystem::temp_directory_path() / ("drom_orient_reach_" + std::to_string(::getpid()));
  std::filesystem::remove_all(out);
  const OrientResult r = run_orient(small_case("corner", {"machine.part_origin=[400.0, 0.0, 0.0]", "check.voxel=1"}), {out, true, true});
  ASSERT_FALSE(r.unreachable.empty());
  EXPECT_NE(r.unreachable.front().find("X = "), std::string::npos) << r.unreachable.front();
  EXPECT_NE(r.unreachable.front().find("beyond its stroke"), std::string::npos) << r.unreachable.front();
  EXPECT_EQ(r.summary["verdict"], "OUT OF THE MACHINE'S REACH");
  EXPECT_EQ(r.summary["machine"]["unreachable_poses_after"].get<std::size_t>(), r.unreachable.size());
  EXPECT_TRUE(std::filesystem::exists(out / "cl.csv"));
  EXPECT_TRUE(std::filesystem::exists(out / "summary.json"));
  EXPECT_FALSE(std::filesystem::exists(out / "program.ngc"));
  // Mounted at the table's centre, the same case is reachable.
  EXPECT_TRUE(run_orient(small_case("corner", {"check.voxel=1"}), {"", true, false}).unreachable.empty());
  std::filesystem::remove_all(out);
}

// Beyond the seed, the machine's singularity: on the UCP 710 (A/C table) the corrected axis of the
// impeller's v = 0.2 passes comes within a fraction of a degree of C's axis (part Z), where the table
// must spin about C to follow. With model.singular_cone = 5° the axis keeps out of that cone (to the
// spring's give), the rotary rates fall, and the result stays collision-free.
TEST(OrientMachine, TheSingularConeKeepsTheAxisOffCsAxis) {
  const std::vector<std::string> pass{"scene.veins=1", "scene.v_first=0.2", "scene.v_last=0.2", "check.voxel=1"};
  auto with = pass;
  with.push_back("model.singular_cone=0.0873");
  const OrientResult off = run_orient(small_case("impeller", pass), {"", true, false});
  const OrientResult on = run_orient(small_case("impeller", with), {"", true, false});
  const auto closest = [](const OrientResult& r) {
    double least = 1e9;
    for (const auto& h : r.passes)
      for (const auto& a : h.samples) least = std::min(least, std::acos(std::min(1.0, std::abs(a.axis.z()))));
    return least * 180 / std::numbers::pi;
  };
  const double rate_off = off.summary["machine"]["max_ratio_to_limit_after"]["velocity"].get<double>();
  const double rate_on = on.summary["machine"]["max_ratio_to_limit_after"]["velocity"].get<double>();
  std::cout << "closest to C's axis: " << closest(off) << " deg without the cone, " << closest(on) << " deg with it; rotary velocity " << rate_off
            << "x -> " << rate_on << "x the limits at the programmed feed\n";
  EXPECT_LT(closest(off), 2.0) << "the pass this test is about comes near the singularity";
  EXPECT_GT(closest(on), 4.0) << "5° cone, stiffness 10 k: the recall and the walls press it 0.8° in";
  EXPECT_LT(rate_on, 0.5 * rate_off);
  EXPECT_TRUE(on.after.collisions.empty()) << on.after.worst_clearance;
}

// Beyond the seed, the jerk: the Khatib force is only C⁰ where a node enters r0, so θ⃛ jumps there. The
// zero-phase filter (model.smoothing, σ = d0 = 2 mm) on the corner (20 mm tool) takes θ's largest
// jerk down by three orders and machine/'s predicted cycle time down with it, and the result is
// proved again: still collision-free.
TEST(OrientMachine, SmoothingTheResultBoundsTheJerkAndShortensTheCycle) {
  const OrientResult raw = run_orient(small_case("corner", {"check.voxel=1"}), {"", true, false});
  const OrientResult smooth = run_orient(small_case("corner", {"check.voxel=1", "model.smoothing=2"}), {"", true, false});
  const double jerk_raw = raw.summary["orientation"]["max_jerk_rad_s3"].get<double>(), jerk = smooth.summary["orientation"]["max_jerk_rad_s3"].get<double>();
  const double cycle_raw = raw.summary["machine"]["cycle_time_after_s"].get<double>(), cycle = smooth.summary["machine"]["cycle_time_after_s"].get<double>();
  std::cout << "corner: max jerk " << jerk_raw << " -> " << jerk << " rad/s^3, cycle time " << cycle_raw << " -> " << cycle << " s (programmed "
            << raw.summary["machine"]["cycle_time_programmed_s"].get<double>() << " s), worst clearance " << raw.after.worst_clearance << " -> "
            << smooth.after.worst_clearance << " mm\n";
  EXPECT_LT(jerk, jerk_raw / 100);
  EXPECT_LT(cycle, 0.9 * cycle_raw);
  EXPECT_TRUE(smooth.after.collisions.empty()) << smooth.after.worst_clearance;
  EXPECT_GT(smooth.after.worst_clearance, 0);
  // The start and end poses stay (odd reflection at the ends).
  EXPECT_NEAR(smooth.passes.front().samples.front().roll, raw.passes.front().samples.front().roll, 1e-12);
  EXPECT_NEAR(smooth.passes.front().samples.back().roll, raw.passes.front().samples.back().roll, 1e-12);
}

// The passes are placed for the case's tool: CL = S + R n moves with the ball's radius.
// drom orient's [relax]: the programmed axis relaxed under the machine's limits (thesis 003 eq. 5),
// checked here against the cutter model rather than the relaxation's own pose formula: at every point
// the contact stays on the cutter's surface, the axis within the tilt bounds of the surface normal,
// and the poses are proved (or not) by the same clearance check as the field's result.
TEST(OrientRelax, TheRelaxedProgrammedAxisKeepsTheContactWithinTheTiltBounds) {
  const OrientCase c = small_case("bump", {"relax.enabled=true", "relax.tilt_min=2", "relax.tilt_max=6"});
  const OrientResult r = run_orient(c, {"", true, false});
  const OrientScene scene = build_orient_scene(c);
  ASSERT_EQ(r.relaxed.size(), scene.passes.size());
  constexpr double degree = std::numbers::pi / 180;
  std::size_t poses = 0;
  for (std::size_t p = 0; p < scene.passes.size(); ++p) {
    const FramedPath& path = scene.passes[p];
    ASSERT_EQ(r.relaxed[p].size(), path.cl.size());
    for (std::size_t i = 0; i < path.cl.size(); ++i, ++poses) {
      const FramedPath::Frame fr = path.at(path.s[i]);
      const Eigen::Vector3d contact = path.cl[i] - scene.tool.cutter.corner_radius * fr.n;
      const machine::ClPose& pose = r.relaxed[p][i];
      EXPECT_NEAR(signed_distance(scene.tool, {pose.tip, pose.axis}, contact), 0, 1e-6) << "pass " << p << " point " << i;
      const double tilt = std::acos(std::clamp(pose.axis.dot(fr.n), -1.0, 1.0));
      EXPECT_GE(tilt, 2 * degree - 1e-9);
      EXPECT_LE(tilt, 6 * degree + 1e-9);
    }
  }
  EXPECT_EQ(r.relaxed_check.poses, poses);
  const auto& s = r.summary["relaxed_programmed_axis"];
  EXPECT_GT(s["time_relaxed_s"].get<double>(), 0);
  EXPECT_EQ(s["passes_relaxed"].get<std::size_t>(), scene.passes.size());
  EXPECT_EQ(s["clearance"]["collisions"].get<std::size_t>(), r.relaxed_check.collisions.size());
  // Its keys are checked like every other.
  try {
    small_case("bump", {"relax.enabled=true", "relax.tilt_min=5", "relax.tilt_max=3"});
    ADD_FAILURE() << "tilt_max below tilt_min was accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("relax.tilt_max"), std::string::npos) << e.what();
  }
}

TEST(OrientScenes, PassesFollowTheCasesTool) {
  const OrientScene r5 = build_orient_scene(small_case("panel"));
  const OrientScene r3 = build_orient_scene(small_case("panel", {"tool.radius=3"}));
  ASSERT_EQ(r5.tool.cutter.radius, 5);
  ASSERT_EQ(r3.tool.cutter.radius, 3);
  const FramedPath& a = r5.passes.front();
  const FramedPath& b = r3.passes.front();
  const Eigen::Vector3d n = a.at(0.5 * a.length()).n;
  // Same surface point under both: the CL points differ by (5 − 3) n.
  const double along = (a.at(0.5 * a.length()).cl - b.at(0.5 * b.length()).cl).dot(n);
  EXPECT_NEAR(along, 2.0, 0.05);
}

}  // namespace
}  // namespace drom::paths
