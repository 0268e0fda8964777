// Issue 6 on a real (coarse) offline database: drom reduce's bound against what it measures, and the
// predictor fed with readings synthesized from the databases themselves: a profile inside the basis
// (check 2), a truth outside it (check 3), and clear errors for the wrong input.
#include "online/predictor.hpp"
#include "tests/online/exact_reading.hpp"
#include "reduce/database_reduction.hpp"
#include "reduce/light_model.hpp"
#include "support/file_integrity.hpp"
#include "support/input_error.hpp"
#include "support/hdf5_reader.hpp"

#include "drom_process.hpp"

#include <gtest/gtest.h>
#include <hdf5.h>
#include <nlohmann/json.hpp>
#include <vtkNew.h>
#include <vtkPointData.h>
#include <vtkUnstructuredGrid.h>
#include <vtkXMLUnstructuredGridReader.h>

#include <Eigen/Dense>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

namespace {

std::string run(const std::string& args) {
  const DromResult r = run_drom(args + " --quiet");
  return r.exit_code == 0 ? "" : "exit " + std::to_string(r.exit_code) + ": " + r.output;
}

std::filesystem::path root() { return std::filesystem::temp_directory_path() / "drom_model_tests"; }

const std::string kPlate =
    " --set mesh.nx=10 --set mesh.ny=10 --set path.station_spacing=300 --set removal.voxel_size=1.0"
    " --set clamps.0.box=[0,100,0,100] --set clamps.1.box=[900,1000,0,100] --set clamps.2.box=[0,100,900,1000] --set clamps.3.box=[900,1000,900,1000]";

Eigen::MatrixXd as_matrix(const drom::Hdf5Matrix& m) {
  return Eigen::Map<const Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>>(m.data.data(), static_cast<Eigen::Index>(m.rows),
                                                                                                    static_cast<Eigen::Index>(m.cols));
}

nlohmann::json summary(const std::filesystem::path& dir) { return nlohmann::json::parse(std::ifstream(dir / "summary.json")); }

// Each test has its own folder (ctest runs them in parallel) with a coarse offline database.
class ModelOnARealDatabase : public ::testing::Test {
 protected:
  void SetUp() override {
    dir_ = root() / ::testing::UnitTest::GetInstance()->current_test_info()->name();
    std::filesystem::remove_all(dir_);
  }
  std::filesystem::path offline(const std::string& basis = "") {
    EXPECT_EQ(run("offline" + kPlate + basis + " --out " + (dir_ / "db").string()), "");
    return dir_ / "db" / "database.h5";
  }
  std::filesystem::path dir_;
};

// Readings at the target nodes at every station, synthesized from a history w(node, station) of the
// database (linear in time between stations, 0 at the start) as a noise-free sensor reads the floor
// (tests/online/exact_reading.hpp), no offsets applied.
struct Readings {
  std::vector<double> times;
  std::vector<std::vector<drom::online::MeasuredPoint>> profiles;
};
Readings readings_from(const drom::reduce::LightModel& model, const Eigen::VectorXd& station_times, const Eigen::MatrixXd& w /* nodes x stations */) {
  const Eigen::Index nodes = w.rows(), stations = w.cols();
  Eigen::VectorXd times(stations + 1);
  times << 0, station_times;
  Eigen::MatrixXd history(nodes, stations + 1);
  history << Eigen::VectorXd::Zero(nodes), w;
  auto at = [&](const drom::reduce::SurfacePoint& p, double t) {
    const auto [i, a] = drom::reduce::locate_time(times, t);
    double v = 0;
    for (int q = 0; q < p.count; ++q) {
      const int n = p.nodes[static_cast<std::size_t>(q)];
      v += p.weights[static_cast<std::size_t>(q)] * ((1 - a) * history(n, i) + a * history(n, i + 1));
    }
    return v;
  };
  const drom::test::ExactReading exact(model, at, [](double) { return 0.0; }, {}, std::vector<double>(times.data(), times.data() + times.size()));
  Readings r;
  for (Eigen::Index s = 0; s < stations; ++s) {
    const double t = station_times[s];
    std::vector<drom::online::MeasuredPoint> pts;
    for (Eigen::Index n = 0; n < nodes; ++n) {
      const Eigen::Vector3d x = model.target.nodes().col(n);
      const double z = exact(x.x(), x.y(), t);
      if (std::isfinite(z)) pts.push_back({x.x(), x.y(), z});
    }
    r.times.push_back(t);
    r.profiles.push_back(std::move(pts));
  }
  return r;
}

}  // namespace

TEST_F(ModelOnARealDatabase, ReduceMeetsItsBoundAndIsSmallerThanTheDatabase) {
  const auto db = offline();
  const auto out = dir_ / "model_default";
  ASSERT_EQ(run("reduce " + db.string() + " --tol 1e-3 --out " + (out / "model.h5").string()), "");
  const auto s = summary(out);
  std::printf("reduce --tol 1e-3: r = %d, bound %.3g mm (POD %.3g, histories %.3g), measured %.3g mm, %.2f MB for a %.2f MB database\n", s["rank"].get<int>(),
              s["error_bound_mm"].get<double>(), s["pod_max_bound_mm"].get<double>(), s["history_bound_mm"].get<double>(), s["measured_max_error_mm"].get<double>(),
              s["model_mb"].get<double>(), s["database_mb"].get<double>());
  EXPECT_LE(s["pod_max_bound_mm"].get<double>(), 1e-3);
  EXPECT_LE(s["history_bound_mm"].get<double>(), 5e-4);
  EXPECT_LE(s["measured_max_error_mm"].get<double>(), s["error_bound_mm"].get<double>());
  EXPECT_LT(s["model_mb"].get<double>(), s["database_mb"].get<double>());
  const auto model = drom::reduce::LightModel::read(out / "model.h5");
  EXPECT_EQ(model.rank(), s["rank"].get<int>());
  EXPECT_GT(model.rank(), 0);
  EXPECT_FALSE(model.has_top());  // not asked for
  // The prior's mean is the case's own [stress] profile: its history is the database's B1 c.
  const drom::Hdf5Reader h5(db);
  const Eigen::MatrixXd B1 = as_matrix(h5.matrix("B1"));
  const Eigen::VectorXd times = as_matrix(h5.matrix("station_time"));
  const Eigen::VectorXd c = (Eigen::VectorXd(6) << -60, 30, -15, -40, 20, -10).finished();
  ASSERT_EQ(model.prior_mean.size(), model.rank());
  const Eigen::Index nodes = model.target.node_count();
  double mean_error = 0;
  for (Eigen::Index st = 0; st < times.size(); ++st) {
    Eigen::VectorXd w = Eigen::VectorXd::Zero(nodes);
    for (int k = 0; k < model.rank(); ++k) w += model.prior_mean[k] * model.histories[static_cast<std::size_t>(k)].at(times[st]);
    mean_error = std::max(mean_error, (w - B1.middleRows(st * nodes, nodes) * c).cwiseAbs().maxCoeff());
  }
  std::printf("prior mean: its history against B1 c (the case's profile) %.3g mm (bound %.3g mm)\n", mean_error, model.error_bound());
  EXPECT_LE(mean_error, model.error_bound());

  // With the stock's top: kept within the margin, its measured error where it still stands.
  ASSERT_EQ(run("reduce " + db.string() + " --tol 1e-3 --top-margin 100 --out " + (out / "with_top.h5").string()), "");
  const auto top = drom::reduce::LightModel::read(out / "with_top.h5");
  ASSERT_TRUE(top.has_top());
  EXPECT_EQ(static_cast<int>(top.top_histories.size()), top.rank());
  EXPECT_GE(top.top.nodes().row(0).minCoeff(), 100.0 - 1e-9);  // the pocket starts at 200
  EXPECT_LE(top.top.nodes().row(0).maxCoeff(), 900.0 + 1e-9);
  EXPECT_GT(top.top_error_bound, 0);
  EXPECT_LT(top.top_error_bound, 1e-3);
  std::printf("with the top (100 mm margin): %d top nodes, measured error %.3g mm where it stands\n", top.top.node_count(), top.top_error_bound);
  // The pictures: the target surface with one history per mode, the final surface with one vector each.
  for (const char* name : {"target_modes.vtu", "final_shape_modes.vtu"}) {
    vtkNew<vtkXMLUnstructuredGridReader> reader;
    reader->SetFileName((out / name).c_str());
    reader->Update();
    vtkUnstructuredGrid* grid = reader->GetOutput();
    EXPECT_GT(grid->GetNumberOfCells(), 0) << name;
    EXPECT_EQ(grid->GetPointData()->GetNumberOfArrays(), std::string(name) == "target_modes.vtu" ? model.rank() + 1 : model.rank()) << name;
  }
}

TEST_F(ModelOnARealDatabase, PredictorRecoversAProfileInsideTheBasis) {
  // Check 2 on the real model: c = s V_r D_r^-1 alpha is a profile whose history is exactly U_r alpha;
  // its readings come from B1 c (the database), not from the model.
  const auto db = offline();
  const auto out = dir_ / "model_tight";
  ASSERT_EQ(run("reduce " + db.string() + " --tol 1e-6 --history-tol 1e-12 --out " + (out / "model.h5").string()), "");
  auto model = drom::reduce::LightModel::read(out / "model.h5");
  const int r = model.rank();
  ASSERT_GE(r, 3);
  Eigen::VectorXd alpha(r);
  for (int k = 0; k < r; ++k) alpha[k] = model.prior_sd[k] * (k % 2 ? -0.7 : 1.1);
  const Eigen::VectorXd c = model.profile_scale * model.right * model.singular_values.head(r).cwiseInverse().asDiagonal() * alpha;
  const drom::Hdf5Reader h5(db);
  const Eigen::MatrixXd B1 = as_matrix(h5.matrix("B1")), B2 = as_matrix(h5.matrix("B2"));
  const Eigen::VectorXd times = as_matrix(h5.matrix("station_time"));
  const Eigen::Index nodes = model.target.node_count();
  const Eigen::VectorXd w = B1 * c;
  const Readings readings = readings_from(model, times, Eigen::Map<const Eigen::MatrixXd>(w.data(), nodes, times.size()));
  drom::online::PredictorSettings settings;
  settings.prior_scale = 1e6;
  settings.reading_range = 100;
  drom::online::Predictor predictor(model, settings);
  for (std::size_t i = 0; i < readings.times.size(); ++i) predictor.add_profile(readings.times[i], {}, readings.profiles[i]);
  const auto e = predictor.estimate();
  const double alpha_error = (e.alpha - alpha).cwiseAbs().maxCoeff() / alpha.cwiseAbs().maxCoeff();
  // Final shape against B2 c at the final surface's nodes.
  const auto shape = predictor.final_shape();
  const Eigen::VectorXd b2 = B2 * c;
  const Eigen::MatrixXd coords = as_matrix(h5.matrix("node_coordinates"));
  double shape_error = 0, shape_max = 0;
  for (Eigen::Index i = 0; i < shape.nodes.cols(); ++i) {
    Eigen::Index node = -1;
    for (Eigen::Index n = 0; n < coords.rows() && node < 0; ++n)
      if ((coords.row(n).transpose() - shape.nodes.col(i)).norm() < 1e-9) node = n;
    ASSERT_GE(node, 0);
    shape_error = std::max(shape_error, (shape.displacement.col(i) - b2.segment<3>(3 * node)).cwiseAbs().maxCoeff());
    shape_max = std::max(shape_max, b2.segment<3>(3 * node).cwiseAbs().maxCoeff());
  }
  std::printf("real model, r = %d: alpha error %.2e (relative), final shape error %.2e mm (max %.3f mm)\n", r, alpha_error, shape_error, shape_max);
  EXPECT_LT(alpha_error, 1e-8);
  EXPECT_LT(shape_error, 1e-6);
}

TEST_F(ModelOnARealDatabase, TruthOutsideTheBasisIsPredictedWithinItsTruncationEstimate) {
  // Check 3: the truth (the case's profile, degrees 2, 4, 6) has higher Legendre content than the
  // basis (degree 2 only). A fuller basis would not do: a pocket of one depth releases a layer whose
  // effect on a thin plate is its force and moment per direction, so the responses to degrees 2 and 4
  // already span any profile's to 5e-6 mm here (measured, degree 8 included).
  // The truncation estimate is what the basis can do at best: the least-squares fit of the truth's
  // whole target-surface history in span(U1), in max norm. The predictor, which only sees
  // differenced readings as they come, must predict the final target surface within twice that plus
  // the model's own bound.
  const auto db = offline(" --set stress.max_degree=2 --set stress.sigma11=[-60] --set stress.sigma22=[-40]");
  ASSERT_EQ(run("truth" + kPlate + " --set truth.max_degree=6 --set truth.sigma11=[-60,30,-15] --set truth.sigma22=[-40,20,-10] --frames 0 --out " + (dir_ / "truth").string()), "");
  const auto out = dir_ / "model_outside";
  ASSERT_EQ(run("reduce " + db.string() + " --tol 1e-4 --out " + (out / "model.h5").string()), "");
  auto model = drom::reduce::LightModel::read(out / "model.h5");
  const int r = model.rank();
  const drom::Hdf5Reader h5(dir_ / "truth" / "database.h5");
  const Eigen::VectorXd truth = as_matrix(h5.matrix("B1"));
  const Eigen::VectorXd times = as_matrix(h5.matrix("station_time"));
  const Eigen::Index nodes = model.target.node_count(), stations = times.size();
  const Eigen::Map<const Eigen::MatrixXd> w(truth.data(), nodes, stations);
  // Best fit of the whole history.
  Eigen::MatrixXd U(nodes * stations, r);
  for (int k = 0; k < r; ++k)
    for (Eigen::Index s = 0; s < stations; ++s) U.col(k).segment(s * nodes, nodes) = model.histories[static_cast<std::size_t>(k)].at(times[s]);
  const Eigen::VectorXd best = U.colPivHouseholderQr().solve(truth);
  const double estimate = (U * best - truth).cwiseAbs().maxCoeff();
  // Online, noise-free readings, the default prior.
  drom::online::PredictorSettings settings;
  settings.noise_sd = 1e-3;
  settings.reading_range = 100;
  drom::online::Predictor predictor(model, settings);
  const Readings readings = readings_from(model, times, w);
  for (std::size_t i = 0; i < readings.times.size(); ++i) predictor.add_profile(readings.times[i], {}, readings.profiles[i]);
  double error = 0;
  for (Eigen::Index n = 0; n < nodes; ++n) {
    const Eigen::Vector3d x = model.target.nodes().col(n);
    error = std::max(error, std::abs(predictor.target_altitude(x.x(), x.y(), times[stations - 1]) - x.z() - w(n, stations - 1)));
  }
  const double max_w = w.col(stations - 1).cwiseAbs().maxCoeff();
  std::printf("truth outside the basis (degrees 4, 6 against 2): final target surface error %.3g mm (max w %.3f mm); truncation estimate %.3g mm, model bound %.3g mm\n", error,
              max_w, estimate, model.error_bound());
  EXPECT_GT(estimate, 10 * model.error_bound());  // the truth really is outside the basis
  EXPECT_LE(error, 2 * estimate + model.error_bound());
}

TEST_F(ModelOnARealDatabase, ReduceRefusesWhatIsNotAnOfflineDatabase) {
  ASSERT_EQ(run("truth" + kPlate + " --set path.station_spacing=3000 --frames 0 --out " + (dir_ / "truth").string()), "");
  DromResult r = run_drom("reduce " + (dir_ / "truth" / "database.h5").string() + " --out " + (dir_ / "bad").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("offline"), std::string::npos) << r.output;
  r = run_drom("reduce " + (dir_ / "missing.h5").string() + " --out " + (dir_ / "bad").string());
  EXPECT_EQ(r.exit_code, 2);
  EXPECT_NE(r.output.find("missing.h5"), std::string::npos) << r.output;
  r = run_drom("reduce " + (dir_ / "truth" / "database.h5").string() + " --tol -1 --out " + (dir_ / "bad").string());
  EXPECT_NE(r.exit_code, 0);
  EXPECT_NE(r.output.find("--tol"), std::string::npos) << r.output;
}

// Finding 28 (docs/robustness.md): a database whose top_parametric had one column, not (u, v, t), was
// read past the end of its matrix while the stock's top was kept (ASan: heap-buffer-overflow in
// reduce_database). Its shape is now checked, and the error names the file and what was expected.
TEST_F(ModelOnARealDatabase, ATopParametricOfTheWrongShapeIsRefusedNamingIt) {
  const std::string coarse =
      " --set mesh.nx=3 --set mesh.ny=3 --set path.station_spacing=400 --set removal.voxel_size=2.0"
      " --set clamps.0.box=[0,200,0,200] --set clamps.1.box=[800,1000,0,200] --set clamps.2.box=[0,200,800,1000] --set clamps.3.box=[800,1000,800,1000]";
  ASSERT_EQ(run("offline" + coarse + " --out " + (dir_ / "db").string()), "");
  const auto db = dir_ / "db" / "database.h5";
  std::size_t top_nodes = 0;
  {
    // Rewritten in place, then sealed again: the file is damaged the way a foreign writer would.
    const hid_t file = H5Fopen(db.c_str(), H5F_ACC_RDWR, H5P_DEFAULT);
    ASSERT_GE(file, 0);
    const hid_t old = H5Dopen2(file, "top_parametric", H5P_DEFAULT);
    const hid_t space = H5Dget_space(old);
    hsize_t dims[2] = {0, 0};
    ASSERT_EQ(H5Sget_simple_extent_ndims(space), 2);
    H5Sget_simple_extent_dims(space, dims, nullptr);
    ASSERT_EQ(dims[1], 3u);
    top_nodes = dims[0];
    H5Sclose(space), H5Dclose(old);
    ASSERT_GE(H5Ldelete(file, "top_parametric", H5P_DEFAULT), 0);
    const std::vector<double> u(top_nodes, 500.0);
    const hsize_t one_column[1] = {top_nodes};
    const hid_t column = H5Screate_simple(1, one_column, nullptr);
    const hid_t set = H5Dcreate2(file, "top_parametric", H5T_NATIVE_DOUBLE, column, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
    ASSERT_GE(H5Dwrite(set, H5T_NATIVE_DOUBLE, H5S_ALL, H5S_ALL, H5P_DEFAULT, u.data()), 0);
    H5Dclose(set), H5Sclose(column), H5Fclose(file);
    drom::seal_file(db);
  }
  drom::reduce::DatabaseReductionSettings settings;
  settings.top_margin = 50;
  std::string error = "no error";
  try {
    drom::reduce::reduce_database(db, settings);
  } catch (const drom::InputError& e) {
    error = e.what();
  }
  EXPECT_EQ(error, db.string() + ": top_parametric is " + std::to_string(top_nodes) + " x 1, expected one row (u, v, t) per top node: " + std::to_string(top_nodes) + " x 3");
}
