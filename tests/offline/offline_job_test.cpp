// Issue 4 checks on coarse versions of both cases: superposition, station interpolation, resume,
// refusing to mix cases, and the physics (panel sag, plate saddle).
#include "offline/offline_job.hpp"
#include "fem/residual_stress.hpp"
#include "support/hdf5_reader.hpp"

#include "drom_process.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <Eigen/Dense>

#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

namespace {

// "" on success, otherwise the exit code and what drom said.
std::string run(const std::string& args) {
  const DromResult r = run_drom(args + " --quiet");
  return r.exit_code == 0 ? "" : "exit " + std::to_string(r.exit_code) + ": " + r.output;
}

std::filesystem::path dir(const std::string& name) {
  const auto d = std::filesystem::temp_directory_path() / "drom_offline_tests" / name;
  std::filesystem::remove_all(d);
  return d;
}

// Coarse flat plate: 100 mm elements, a station every 300 mm of cut, 1 mm voxels.
const std::string kPlate =
    " --set mesh.nx=10 --set mesh.ny=10 --set path.station_spacing=300 --set removal.voxel_size=1.0"
    " --set clamps.0.box=[0,100,0,100] --set clamps.1.box=[900,1000,0,100] --set clamps.2.box=[0,100,900,1000] --set clamps.3.box=[900,1000,900,1000]";
const std::string kPanel = std::string(DROM_SOURCE_DIR) + "/cases/curved_panel.toml --set mesh.nx=12 --set mesh.ny=12 --set path.station_spacing=150"
                                                          " --set removal.voxel_size=0.5";

Eigen::MatrixXd as_matrix(const drom::Hdf5Matrix& m) {
  Eigen::MatrixXd r(static_cast<Eigen::Index>(m.rows), static_cast<Eigen::Index>(m.cols));
  for (std::size_t i = 0; i < m.rows; ++i)
    for (std::size_t j = 0; j < m.cols; ++j) r(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(j)) = m(i, j);
  return r;
}

// The cases' [truth] profiles lie outside their bases on purpose (drom run); these tests check the
// truth run against the [stress] profile, so they make it the truth.
const std::string kPlateStressTruth = " --set truth.max_degree=6 --set truth.sigma11=[-60,30,-15] --set truth.sigma22=[-40,20,-10]";
const std::string kPanelStressTruth = " --set truth.max_degree=7 --set truth.sigma11=[40,-15,5] --set truth.sigma22=[15,-5,2]";

double relative(const Eigen::MatrixXd& a, const Eigen::MatrixXd& b) { return (a - b).cwiseAbs().maxCoeff() / b.cwiseAbs().maxCoeff(); }

}  // namespace

TEST(Offline, TruthEqualsSuperposedUnitResponses) {
  const auto off = dir("super_offline"), tru = dir("super_truth");
  ASSERT_EQ(run("offline" + kPlate + kPlateStressTruth + " --frames 2 --out " + off.string()), "");
  ASSERT_EQ(run("truth" + kPlate + kPlateStressTruth + " --out " + tru.string()), "");
  drom::Hdf5Reader db(off / "database.h5"), truth(tru / "database.h5");
  EXPECT_EQ(db.text_attribute("kind"), "offline");
  EXPECT_EQ(db.text_attribute("case_hash"), truth.text_attribute("case_hash"));
  // The case's profile in the unit basis: sigma11 coefficients, then sigma22.
  const drom::fem::StressProfile profile{{2, 4, 6}, {-60, 30, -15}, {-40, 20, -10}};
  const Eigen::VectorXd a = drom::fem::profile_weights(profile);
  const Eigen::MatrixXd B1 = as_matrix(db.matrix("B1")), B2 = as_matrix(db.matrix("B2"));
  ASSERT_EQ(B1.cols(), 6);
  const double e1 = relative(B1 * a, as_matrix(truth.matrix("B1"))), e2 = relative(B2 * a, as_matrix(truth.matrix("B2")));
  std::printf("superposition: B1 a vs truth %.2e, B2 a vs truth %.2e (relative)\n", e1, e2);
  EXPECT_LT(e1, 1e-8);
  EXPECT_LT(e2, 1e-8);
  const double e3 = relative(as_matrix(db.matrix("B1_top")) * a, as_matrix(truth.matrix("B1_top")));
  EXPECT_LT(e3, 1e-8);
  EXPECT_GT(as_matrix(truth.matrix("B1")).cwiseAbs().maxCoeff(), 1e-3);  // something moved

  // The stock's top (B1_top) is the part's top face: where the tool has not been yet, a thin plate's
  // top moves with the floor 2 mm below it (bending; the difference is the through-thickness strain).
  // Checked at the first station (300 mm into the first pass, at y = 212.5) for y > 400.
  const Eigen::MatrixXd target_xyz = as_matrix(truth.matrix("target_coordinates")), top_ids = as_matrix(truth.matrix("top_nodes")),
                        xyz = as_matrix(truth.matrix("node_coordinates")), W = as_matrix(truth.matrix("B1")), W_top = as_matrix(truth.matrix("B1_top"));
  EXPECT_NEAR(xyz.col(2).maxCoeff(), 10.0, 1e-9);
  double largest = 0, difference = 0;
  int pairs = 0;
  for (Eigen::Index j = 0; j < top_ids.rows(); ++j) {
    const Eigen::Vector3d p = xyz.row(static_cast<Eigen::Index>(top_ids(j, 0))).transpose();
    EXPECT_NEAR(p.z(), 10.0, 1e-9);
    for (Eigen::Index i = 0; i < target_xyz.rows(); ++i)
      if (std::abs(target_xyz(i, 0) - p.x()) < 1e-6 && std::abs(target_xyz(i, 1) - p.y()) < 1e-6 && p.y() > 400) {
        largest = std::max(largest, std::abs(W(i, 0)));
        difference = std::max(difference, std::abs(W_top(j, 0) - W(i, 0)));
        ++pairs;
      }
  }
  std::printf("stock top vs floor where uncut, first station: %d pairs, max |w| %.3e mm, max difference %.3e mm\n", pairs, largest, difference);
  EXPECT_GT(pairs, 10);
  EXPECT_GT(largest, 0);
  EXPECT_LT(difference, 0.05 * largest);
  EXPECT_TRUE(std::filesystem::exists(tru / "truth.pvd"));
  EXPECT_TRUE(std::filesystem::exists(tru / "final_free_shape.vtu"));
  EXPECT_FALSE(std::filesystem::exists(off / ".checkpoint"));
  EXPECT_TRUE(std::filesystem::exists(off / "offline.pvd"));  // --frames 2: unit-profile fields at two stations
  EXPECT_EQ(std::distance(std::filesystem::directory_iterator(off / "frames"), std::filesystem::directory_iterator{}), 2);
}

TEST(Offline, PgdDatabaseMatchesTheFeDatabaseOnTheSameHex27Mesh) {
  // Issue 5: solver.kind = "pgd" produces the same B1 / B2 as the 3D FE core on the same Hex27 tensor
  // space: both hold the same clamps (penalty vs elimination) and align the free shape by best fit
  // (foundation vs 3-2-1); the D.12 tolerance is the case default (1e-3).
  const auto fe = dir("pgd_fe"), pgd = dir("pgd_pgd");
  const std::string hex27 = kPlate + " --set mesh.element=hex27";
  ASSERT_EQ(run("truth" + hex27 + " --out " + fe.string()), "");
  ASSERT_EQ(run("truth" + hex27 + " --set solver.kind=pgd --frames 2 --out " + pgd.string()), "");
  drom::Hdf5Reader a(fe / "database.h5"), b(pgd / "database.h5");
  const Eigen::MatrixXd B1 = as_matrix(b.matrix("B1")), B2 = as_matrix(b.matrix("B2"));
  const double e1 = relative(B1, as_matrix(a.matrix("B1"))), e2 = relative(B2, as_matrix(a.matrix("B2")));
  std::printf("PGD vs FE databases: B1 %.2e, B2 %.2e (max difference / max FE value)\n", e1, e2);
  EXPECT_LT(e1, 1e-3);
  EXPECT_LT(e2, 1e-3);
  EXPECT_EQ(B1.rows(), a.matrix("B1").rows);
  EXPECT_TRUE(std::filesystem::exists(pgd / "truth.pvd"));
  EXPECT_TRUE(std::filesystem::exists(pgd / "final_free_shape.vtu"));
  EXPECT_TRUE(std::filesystem::exists(pgd / "final_free_shape_modes.h5"));
  drom::Hdf5Reader modes(pgd / "final_free_shape_modes.h5");
  EXPECT_EQ(modes.matrix("X_w").rows, 21u * 21u);  // 10 x 10 Quad9 nodes
  EXPECT_EQ(modes.matrix("Z_w").rows, 11u);        // 5 Line3 through the thickness
  EXPECT_EQ(modes.matrix("X_w").cols, modes.matrix("Z_w").cols);
}

TEST(Offline, PgdRunDoesNotDependOnThreadsOrResumes) {
  // Warm starts run within fixed chunks of stations that start cold, so neither the thread count nor
  // an interruption changes what is solved.
  const auto whole = dir("pgd_whole"), parts = dir("pgd_parts");
  const std::string pgd = kPlate + " --set mesh.element=hex27 --set solver.kind=pgd --set path.station_spacing=600";
  ASSERT_EQ(run("truth" + pgd + " --threads 2 --out " + whole.string()), "");
  ASSERT_EQ(run("truth" + pgd + " --threads 1 --stop-after 21 --out " + parts.string()), "");
  ASSERT_EQ(run("truth" + pgd + " --threads 2 --resume --out " + parts.string()), "");
  drom::Hdf5Reader a(whole / "database.h5"), b(parts / "database.h5");
  EXPECT_EQ(a.text_attribute("content_hash"), b.text_attribute("content_hash"));
}

TEST(Offline, ResumedRunWritesTheSameDatabase) {
  const auto whole = dir("resume_whole"), parts = dir("resume_parts");
  ASSERT_EQ(run("truth" + kPlate + " --out " + whole.string()), "");
  ASSERT_EQ(run("truth" + kPlate + " --stop-after 7 --out " + parts.string()), "");  // "killed" after 7 stations
  EXPECT_TRUE(std::filesystem::exists(parts / ".checkpoint"));
  EXPECT_FALSE(std::filesystem::exists(parts / "database.h5"));
  // A plain rerun refuses to overwrite, and a different case refuses to mix.
  EXPECT_NE(run("truth" + kPlate + " --out " + parts.string()).find("pass --resume"), std::string::npos);
  EXPECT_NE(run("truth" + kPlate + " --set stress.sigma11=[1,2,3] --resume --out " + parts.string()).find("different case"), std::string::npos);
  ASSERT_EQ(run("truth" + kPlate + " --stop-after 5 --resume --out " + parts.string()), "");
  ASSERT_EQ(run("truth" + kPlate + " --resume --out " + parts.string()), "");
  drom::Hdf5Reader a(whole / "database.h5"), b(parts / "database.h5");
  EXPECT_EQ(a.text_attribute("content_hash"), b.text_attribute("content_hash"));
  for (const char* name : {"B1", "B2", "station_time", "station_position", "target_coordinates"})
    EXPECT_EQ(a.matrix(name).data, b.matrix(name).data) << name;
  // Byte for byte, too: no timestamps in the file.
  std::ifstream fa(whole / "database.h5", std::ios::binary), fb(parts / "database.h5", std::ios::binary);
  const std::string ba((std::istreambuf_iterator<char>(fa)), {}), bb((std::istreambuf_iterator<char>(fb)), {});
  EXPECT_TRUE(ba == bb);
}

// Issue 44: a new job into a finished job's folder clears that job's outputs first (support/summary.hpp),
// so one stopped midway leaves no database.h5 or summary.json of the earlier one beside its stations.
TEST(Offline, ARerunStoppedMidwayLeavesNothingOfTheFinishedJobBefore) {
  const auto out = dir("rerun_stopped");
  ASSERT_EQ(run("truth" + kPlate + " --out " + out.string()), "");
  ASSERT_TRUE(std::filesystem::exists(out / "database.h5") && std::filesystem::exists(out / "summary.json"));
  std::filesystem::create_directories(out / "mine");
  std::ofstream(out / "mine" / "notes.txt") << "the user's\n";
  ASSERT_EQ(run("truth" + kPlate + " --stop-after 2 --out " + out.string()), "");
  EXPECT_FALSE(std::filesystem::exists(out / "database.h5"));
  EXPECT_FALSE(std::filesystem::exists(out / "summary.json"));
  EXPECT_FALSE(std::filesystem::exists(out / "frames"));
  EXPECT_TRUE(std::filesystem::exists(out / ".checkpoint"));
  EXPECT_TRUE(std::filesystem::exists(out / "mine" / "notes.txt"));  // not the earlier job's
  ASSERT_EQ(run("truth" + kPlate + " --resume --out " + out.string()), "");
  EXPECT_TRUE(std::filesystem::exists(out / "database.h5"));
}

TEST(Offline, StationInterpolationErrorIsBounded) {
  // Stations every 300 mm, and every 150 mm (which adds the midpoints): interpolate the coarse run
  // linearly in time at the fine run's extra stations.
  const auto coarse = dir("interp_coarse"), fine = dir("interp_fine");
  ASSERT_EQ(run("truth" + kPlate + " --out " + coarse.string()), "");
  ASSERT_EQ(run("truth" + kPlate + " --set path.station_spacing=150 --out " + fine.string()), "");
  drom::Hdf5Reader c(coarse / "database.h5"), f(fine / "database.h5");
  const auto tc = c.matrix("station_time"), tf = f.matrix("station_time");
  const Eigen::MatrixXd Bc = as_matrix(c.matrix("B1")), Bf = as_matrix(f.matrix("B1"));
  const auto nt = static_cast<Eigen::Index>(c.matrix("target_nodes").rows);
  double worst = 0, worst_step = 0;
  for (std::size_t k = 0; k + 1 < tc.rows; ++k) {
    worst_step = std::max(worst_step, (Bc.middleRows(static_cast<Eigen::Index>(k + 1) * nt, nt) - Bc.middleRows(static_cast<Eigen::Index>(k) * nt, nt)).cwiseAbs().maxCoeff());
    for (std::size_t j = 0; j < tf.rows; ++j) {
      const double t = tf.data[j];
      if (t <= tc.data[k] + 1e-9 || t >= tc.data[k + 1] - 1e-9) continue;
      const double s = (t - tc.data[k]) / (tc.data[k + 1] - tc.data[k]);
      const Eigen::MatrixXd interp = (1 - s) * Bc.middleRows(static_cast<Eigen::Index>(k) * nt, nt) + s * Bc.middleRows(static_cast<Eigen::Index>(k + 1) * nt, nt);
      worst = std::max(worst, (interp - Bf.middleRows(static_cast<Eigen::Index>(j) * nt, nt)).cwiseAbs().maxCoeff());
    }
  }
  std::printf("station interpolation: max error %.2e mm, largest change between stations %.2e mm\n", worst, worst_step);
  EXPECT_GT(worst_step, 0);
  EXPECT_LE(worst, 0.5 * worst_step);
}

TEST(Offline, PanelSagsMostInThePocketsMiddleAndMoreAsMaterialGoes) {
  const auto out = dir("panel");
  ASSERT_EQ(run("truth " + kPanel + kPanelStressTruth + " --out " + out.string()), "");
  drom::Hdf5Reader db(out / "database.h5");
  const Eigen::MatrixXd B1 = as_matrix(db.matrix("B1"));
  const auto xyz = db.matrix("target_coordinates");
  const auto nt = static_cast<Eigen::Index>(xyz.rows);
  const auto ns = static_cast<Eigen::Index>(db.matrix("station_time").rows);
  // The node nearest the pocket's centre (x = 225, y = 225).
  Eigen::Index centre = 0;
  double best = 1e300;
  for (Eigen::Index i = 0; i < nt; ++i) {
    const double d = std::hypot(xyz(static_cast<std::size_t>(i), 0) - 225, xyz(static_cast<std::size_t>(i), 1) - 225);
    if (d < best) best = d, centre = i;
  }
  const Eigen::VectorXd last = B1.middleRows((ns - 1) * nt, nt).col(0);
  Eigen::Index deepest = 0;
  last.cwiseAbs().maxCoeff(&deepest);
  const double xd = xyz(static_cast<std::size_t>(deepest), 0), yd = xyz(static_cast<std::size_t>(deepest), 1);
  std::printf("panel: centre w %.4f mm at the last station, max |w| %.4f mm at (%.0f, %.0f)\n", last[centre], last.cwiseAbs().maxCoeff(), xd, yd);
  // The floor sags most in the pocket's middle half. On this coarse mesh it does so in a shallow W
  // along the curved direction, 7 % deeper at x = 150 and 300 than at the centre (with exact removal,
  // issue 29; the leaking volume fractions had left a stiffening skin and a U within 2 %).
  EXPECT_GE(xd, 150 - 1e-6);
  EXPECT_LE(xd, 300 + 1e-6);
  EXPECT_GE(yd, 150 - 1e-6);
  EXPECT_LE(yd, 300 + 1e-6);
  EXPECT_NEAR(std::abs(last[centre]), last.cwiseAbs().maxCoeff(), 0.1 * last.cwiseAbs().maxCoeff());
  // Sag at the centre grows with removed material: compare quarter, half and end of the run.
  const double q = std::abs(B1(((ns - 1) / 4) * nt + centre, 0)), h = std::abs(B1(((ns - 1) / 2) * nt + centre, 0));
  std::printf("panel: centre |w| at 1/4, 1/2, end of the stations: %.4f, %.4f, %.4f mm\n", q, h, std::abs(last[centre]));
  EXPECT_LT(q, h);
  EXPECT_LT(h, std::abs(last[centre]));
}

TEST(Offline, PlateWithOppositeProfilesEndsAsASaddle) {
  const auto out = dir("saddle");
  ASSERT_EQ(run("truth" + kPlate + " --set truth.max_degree=6 --set truth.sigma11=[-60,30,-15] --set truth.sigma22=[60,-30,15] --out " + out.string()), "");
  drom::Hdf5Reader db(out / "database.h5");
  const auto nodes = db.matrix("node_coordinates");
  const Eigen::MatrixXd B2 = as_matrix(db.matrix("B2"));
  // Fit w = c0 + c1 x + c2 y + c3 x^2 + c4 xy + c5 y^2 over the bottom face.
  std::vector<Eigen::Matrix<double, 1, 6>> rows;
  std::vector<double> w;
  for (std::size_t n = 0; n < nodes.rows; ++n) {
    if (nodes(n, 2) > 1e-9) continue;
    const double x = nodes(n, 0) - 500, y = nodes(n, 1) - 500;
    rows.push_back((Eigen::Matrix<double, 1, 6>() << 1, x, y, x * x, x * y, y * y).finished());
    w.push_back(B2(static_cast<Eigen::Index>(3 * n + 2), 0));
  }
  Eigen::MatrixXd A(static_cast<Eigen::Index>(rows.size()), 6);
  Eigen::VectorXd b(static_cast<Eigen::Index>(rows.size()));
  for (std::size_t i = 0; i < rows.size(); ++i) A.row(static_cast<Eigen::Index>(i)) = rows[i], b[static_cast<Eigen::Index>(i)] = w[i];
  const Eigen::VectorXd c = A.colPivHouseholderQr().solve(b);
  std::printf("free final shape: kx %.3e, ky %.3e 1/mm\n", -2 * c[3], -2 * c[5]);
  EXPECT_LT(c[3] * c[5], 0);  // curvatures of opposite signs: a saddle
}

namespace {

void expect_same_database(const std::filesystem::path& a_dir, const std::filesystem::path& b_dir) {
  drom::Hdf5Reader a(a_dir / "database.h5"), b(b_dir / "database.h5");
  EXPECT_EQ(a.text_attribute("content_hash"), b.text_attribute("content_hash")) << a_dir << " against " << b_dir;
  for (const char* name : {"B1", "B2", "B1_top", "station_time"}) EXPECT_EQ(a.matrix(name).data, b.matrix(name).data) << name;
}

}  // namespace

TEST(Offline, OnePassForBothDatabasesWritesWhatTwoPassesWrite) {
  // drom run computes the offline snapshots and the truth in one machining pass when neither is
  // there; each database must be the one its own command writes (the truth's profile has a higher
  // degree, so a shared quadrature or a shared triangular solve would show here).
  const auto loop = dir("one_pass_run");
  ASSERT_EQ(run("run" + kPlate + " --out " + loop.string()), "");
  const auto summary = nlohmann::json::parse(std::ifstream(loop / "summary.json"));
  EXPECT_TRUE(summary["timing_s"]["offline_and_truth_in_one_pass"].get<bool>());
  const auto offline = dir("one_pass_offline"), truth = dir("one_pass_truth");
  ASSERT_EQ(run("offline " + (loop / "offline" / "case.toml").string() + " --out " + offline.string()), "");
  ASSERT_EQ(run("truth " + (loop / "truth" / "case.toml").string() + " --out " + truth.string()), "");
  expect_same_database(loop / "offline", offline);
  expect_same_database(loop / "truth", truth);

  // Interrupted, then resumed with one of the two checkpoints lost: the pass recomputes what that
  // database misses, and both come out the same again.
  drom::offline::JobOptions off, tru;
  off.quiet = tru.quiet = true;
  const auto off_case = drom::case_file::load_case(loop / "offline" / "case.toml", {}), tru_case = drom::case_file::load_case(loop / "truth" / "case.toml", {});
  off.out = dir("one_pass_parts_offline");
  tru.out = dir("one_pass_parts_truth");
  off.stop_after = 5;
  const auto stopped = drom::offline::run_offline_and_truth(off_case, off, tru_case, tru);
  EXPECT_FALSE(stopped.first.finished);
  EXPECT_EQ(stopped.first.stations_saved, 5u);
  EXPECT_FALSE(std::filesystem::exists(off.out / "database.h5"));
  std::filesystem::remove_all(tru.out / ".checkpoint");
  off.stop_after = -1;
  off.resume = true;
  const auto resumed = drom::offline::run_offline_and_truth(off_case, off, tru_case, tru);
  EXPECT_TRUE(resumed.first.finished && resumed.second.finished);
  expect_same_database(off.out, offline);
  expect_same_database(tru.out, truth);
}

namespace {

nlohmann::json block_statistics(const std::filesystem::path& out) {
  return nlohmann::json::parse(std::ifstream(out / "summary.json"))["solver_statistics"]["block"];
}

// Issue 28: a full factorization per chunk of 16 stations and only the machined block at the others,
// against a full factorization at every station, on both removal criteria. Two full factorizations
// that differ only in elimination order already differ by about 1e-8 of the database's largest value
// on these thin, stretched elements (docs/benchmarks.md), so the bound is 5e-8, not 1e-9.
void expect_block_writes_the_full_factorizations_database(const char* name, const std::string& setup) {
  for (const char* criterion : {"volume_fraction", "centroid"}) {
    const std::string label = std::string(name) + "_" + criterion;
    const auto full = dir("block_full_" + label), block = dir("block_" + label);
    const std::string args = " " + setup + " --set removal.criterion=" + criterion;
    ASSERT_EQ(run("truth" + args + " --set solver.stations_per_factorization=1 --out " + full.string()), "");
    ASSERT_EQ(run("truth" + args + " --out " + block.string()), "");
    auto per_station = [](const std::filesystem::path& out) {
      return nlohmann::json::parse(std::ifstream(out / "summary.json"))["time_per_station_s"].get<double>();
    };
    std::printf("%s: %.3f s per station in full, %.3f s with the block\n", label.c_str(), per_station(full), per_station(block));
    drom::Hdf5Reader a(full / "database.h5"), b(block / "database.h5");
    for (const char* matrix : {"B1", "B1_top"}) {
      const Eigen::MatrixXd A = as_matrix(a.matrix(matrix)), B = as_matrix(b.matrix(matrix));
      EXPECT_LT(relative(B, A), 5e-8) << label << " " << matrix;
    }
    const auto stats = block_statistics(block);
    EXPECT_GT(stats["anchors"].get<int>(), 0) << label;
    // Every chunk's later stations refactorized their block or changed nothing (the last chunk may
    // hold one station only).
    EXPECT_GT(stats["block_refactorizations"].get<int>(), 0) << label;
    EXPECT_GE(stats["block_refactorizations"].get<int>() + stats["unchanged_stations"].get<int>() + 1, stats["anchors"].get<int>()) << label;
    EXPECT_EQ(stats["residual_fallbacks"].get<int>(), 0) << label;
    EXPECT_EQ(block_statistics(full)["anchors"].get<int>(), 0) << label;
  }
}

}  // namespace

TEST(Offline, BlockRefactorizationWritesTheFullFactorizationsDatabase) {
  expect_block_writes_the_full_factorizations_database("plate", kPlate + kPlateStressTruth);
}

TEST(Offline, BlockRefactorizationWritesTheFullFactorizationsDatabaseOnThePanel) {
  // On the coarse panel (12 x 12 x 3) 16 stations sweep most of the pocket: the block would not pay,
  // and the job factorizes those chunks in full. Chunks of 2 stations compare the block path there.
  expect_block_writes_the_full_factorizations_database("panel", kPanel + kPanelStressTruth + " --set solver.stations_per_factorization=2");
}

TEST(Offline, AFailedResidualCheckRefactorizesInFull) {
  // A residual bound no solve meets: every station's block solve fails it and is solved again on a
  // full factorization, so the database is the full path's, byte for byte.
  const auto full = dir("fallback_full"), forced = dir("fallback_forced");
  ASSERT_EQ(run("truth" + kPlate + " --set solver.stations_per_factorization=1 --out " + full.string()), "");
  ASSERT_EQ(run("truth" + kPlate + " --set solver.residual_bound=1e-300 --out " + forced.string()), "");
  drom::Hdf5Reader a(full / "database.h5"), b(forced / "database.h5");
  for (const char* name : {"B1", "B2", "B1_top"}) EXPECT_EQ(a.matrix(name).data, b.matrix(name).data) << name;  // (the case, hashed too, differs)
  const auto stats = block_statistics(forced);
  const int stations = nlohmann::json::parse(std::ifstream(forced / "summary.json"))["stations"].get<int>();
  EXPECT_GT(stats["anchors"].get<int>(), 1);
  EXPECT_EQ(stats["residual_fallbacks"].get<int>(), stations);
  EXPECT_EQ(stats["block_refactorizations"].get<int>(), stations - stats["anchors"].get<int>());
}

TEST(Offline, FeBlockRunDoesNotDependOnThreadsResumesOrSlices) {
  // Each chunk of stations starts from its own full factorization, with the whole chunk's block, so
  // neither the thread count, nor an interruption mid-chunk, nor a slice boundary mid-chunk changes
  // what is solved.
  const auto whole = dir("fe_block_whole"), parts = dir("fe_block_parts"), slices = dir("fe_block_slices");
  ASSERT_EQ(run("truth" + kPlate + " --threads 2 --out " + whole.string()), "");
  ASSERT_EQ(run("truth" + kPlate + " --threads 1 --stop-after 21 --out " + parts.string()), "");
  ASSERT_EQ(run("truth" + kPlate + " --threads 2 --resume --out " + parts.string()), "");
  ASSERT_EQ(run("truth" + kPlate + " --threads 1 --stations 0:25 --out " + slices.string()), "");
  ASSERT_EQ(run("truth" + kPlate + " --threads 2 --stations 25: --out " + slices.string()), "");
  ASSERT_EQ(run("merge" + kPlate + " --kind truth --out " + slices.string()), "");
  drom::Hdf5Reader a(whole / "database.h5"), b(parts / "database.h5"), c(slices / "database.h5");
  EXPECT_EQ(a.text_attribute("content_hash"), b.text_attribute("content_hash"));
  EXPECT_EQ(a.text_attribute("content_hash"), c.text_attribute("content_hash"));
  EXPECT_GT(block_statistics(whole)["block_refactorizations"].get<int>(), 0);
}
