// The light model file: what is written is what is read, and a wrong file is named in the error.
#include "reduce/database_reduction.hpp"
#include "reduce/light_model.hpp"
#include "support/file_format.hpp"
#include "support/version.hpp"
#include "support/hdf5_writer.hpp"
#include "support/input_error.hpp"
#include "tests/reduce/synthetic_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <functional>
#include <string>

using namespace drom;

TEST(LightModel, RoundTripsThroughItsHdf5File) {
  const reduce::LightModel m = test::synthetic_model();
  const auto file = std::filesystem::temp_directory_path() / "drom_light_model_test.h5";
  m.write(file);
  const reduce::LightModel back = reduce::LightModel::read(file);
  ASSERT_EQ(back.rank(), m.rank());
  EXPECT_EQ(back.target.node_count(), m.target.node_count());
  EXPECT_EQ(back.target.faces(), m.target.faces());
  EXPECT_EQ(back.target_cut_time, m.target_cut_time);  // inf (never cut) survives as well
  // The bulky factors are stored in single precision (the reduction rounds them before measuring its
  // bound); everything else exactly.
  auto single = [](const Eigen::MatrixXd& a) { return Eigen::MatrixXd(a.cast<float>().cast<double>()); };
  for (int k = 0; k < m.rank(); ++k) {
    EXPECT_EQ(back.histories[static_cast<std::size_t>(k)].space(), single(m.histories[static_cast<std::size_t>(k)].space()));
    EXPECT_EQ(back.histories[static_cast<std::size_t>(k)].time(), single(m.histories[static_cast<std::size_t>(k)].time()));
    EXPECT_NEAR(back.histories[static_cast<std::size_t>(k)].at(17, 33.3), m.histories[static_cast<std::size_t>(k)].at(17, 33.3), 1e-8);
  }
  EXPECT_EQ(back.final_basis, single(m.final_basis));
  EXPECT_EQ(back.path, m.path);
  EXPECT_EQ(back.prior_sd, m.prior_sd);
  EXPECT_EQ(back.case_toml, m.case_toml);
  EXPECT_EQ(back.tool_radius, m.tool_radius);
  EXPECT_FALSE(back.has_top());
  std::filesystem::remove(file);
}

TEST(LightModel, RoundTripsTheStockTop) {
  reduce::LightModel m = test::synthetic_model();
  test::add_synthetic_top(m);
  m.top_history_bound = 1e-5, m.top_error_bound = 2e-5;
  const auto file = std::filesystem::temp_directory_path() / "drom_light_model_top_test.h5";
  m.write(file);
  const reduce::LightModel back = reduce::LightModel::read(file);
  ASSERT_TRUE(back.has_top());
  EXPECT_EQ(back.top.node_count(), m.top.node_count());
  EXPECT_EQ(back.top.faces(), m.top.faces());
  EXPECT_EQ(back.top_cut_time, m.top_cut_time);
  EXPECT_EQ(back.top_error_bound, 2e-5);
  for (int k = 0; k < m.rank(); ++k)
    EXPECT_NEAR(back.top_histories[static_cast<std::size_t>(k)].at(40, 71.2), m.top_histories[static_cast<std::size_t>(k)].at(40, 71.2), 1e-8);
  std::filesystem::remove(file);
}

TEST(LightModel, ReadingAnotherFileNamesItAndWhatIsWrong) {
  const auto file = std::filesystem::temp_directory_path() / "drom_not_a_model.h5";
  {
    Hdf5Writer h5(file);
    h5.attribute("format", std::string("something else"));
    h5.commit();
  }
  try {
    reduce::LightModel::read(file);
    FAIL() << "no error";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(file.string()), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("format"), std::string::npos) << e.what();
  }
  std::filesystem::remove(file);
  EXPECT_THROW(reduce::LightModel::read(file), InputError);  // missing file
}

namespace {

std::string error_reading(const std::function<void()>& read) {
  try {
    read();
  } catch (const InputError& e) {
    return e.what();
  }
  return "no error";
}

}  // namespace

TEST(LightModel, AnotherFormatVersionOrATruncatedFileIsRefusedSayingWhy) {
  const auto dir = std::filesystem::temp_directory_path() / "drom_format_versions";
  std::filesystem::create_directories(dir);
  const reduce::LightModel m = test::synthetic_model();
  m.write(dir / "model.h5");
  // A future version: what made it, what this drom reads, and what to do.
  {
    Hdf5Writer h5(dir / "future.h5");
    write_file_format(h5, {kLightModel.name, kLightModel.version + 1});
    h5.commit();
  }
  const std::string future = error_reading([&] { reduce::LightModel::read(dir / "future.h5"); });
  EXPECT_NE(future.find((dir / "future.h5").string()), std::string::npos) << future;
  EXPECT_NE(future.find("format version " + std::to_string(kLightModel.version + 1) + ", made by drom " + std::string(kVersion)), std::string::npos) << future;
  EXPECT_NE(future.find("reads drom light model format version " + std::to_string(kLightModel.version) + ": update drom"), std::string::npos) << future;
  // A file from before format versions (drom 0.1 wrote "drom light model 1" and nothing else).
  {
    Hdf5Writer h5(dir / "old.h5");
    h5.attribute("format", std::string("drom light model 1"));
    h5.commit();
  }
  EXPECT_NE(error_reading([&] { reduce::LightModel::read(dir / "old.h5"); }).find("before format versions"), std::string::npos);
  // Truncated: the file is named and nothing is read from it.
  const auto size = std::filesystem::file_size(dir / "model.h5");
  std::filesystem::copy_file(dir / "model.h5", dir / "truncated.h5", std::filesystem::copy_options::overwrite_existing);
  std::filesystem::resize_file(dir / "truncated.h5", size / 3);
  const std::string truncated = error_reading([&] { reduce::LightModel::read(dir / "truncated.h5"); });
  EXPECT_NE(truncated.find((dir / "truncated.h5").string() + ": truncated: " + std::to_string(size / 3) + " bytes of the " + std::to_string(size)),
            std::string::npos)
      << truncated;
  // A snapshot database of another version goes the same way through the reduce stage.
  {
    Hdf5Writer h5(dir / "database.h5");
    write_file_format(h5, {kSnapshotDatabase.name, 1});
    h5.commit();
  }
  const std::string old_db = error_reading([&] { reduce::reduce_database(dir / "database.h5", {}); });
  EXPECT_NE(old_db.find("format version 1"), std::string::npos) << old_db;
  EXPECT_NE(old_db.find("write it again with this drom"), std::string::npos) << old_db;
  std::filesystem::remove_all(dir);
}

// Issue 27: what the *_fields fuzzers found in sealed files with wrong content (docs/robustness.md).
TEST(LightModel, CountsAndNumbersFromTheFileAreCheckedBeforeUse) {
  const auto dir = std::filesystem::temp_directory_path() / "drom_hostile_fields";
  std::filesystem::create_directories(dir);
  // The finding: a face-node count of -1.8e308 was cast to int (UBSan); every count read is now a
  // whole number in range first. The same for the rank:
  {
    Hdf5Writer h5(dir / "model.h5");
    write_file_format(h5, kLightModel);
    h5.attribute("case", std::string("name = 'x'"));
    h5.attribute("database_hash", std::string("0"));
    h5.attribute("rank", -1.79769e308);
    h5.commit();
  }
  const std::string rank = error_reading([&] { reduce::LightModel::read(dir / "model.h5"); });
  EXPECT_NE(rank.find((dir / "model.h5").string() + ": rank is -"), std::string::npos) << rank;
  EXPECT_NE(rank.find("expected a whole number in [0, 100000]"), std::string::npos) << rank;
  // The finding: a NaN station time reached the POD, whose std::invalid_argument was no InputError.
  {
    Hdf5Writer h5(dir / "database.h5");
    write_file_format(h5, kSnapshotDatabase);
    h5.attribute("kind", std::string("offline"));
    h5.attribute("case_name", std::string("x"));
    h5.write("B1", std::vector<double>{1, 2, 3, 4}, 2, 2);
    h5.write("station_time", std::vector<double>{0, std::nan("")}, 2, 1);
    h5.commit();
  }
  const std::string nan = error_reading([&] { reduce::reduce_database(dir / "database.h5", {}); });
  EXPECT_NE(nan.find((dir / "database.h5").string() + ": dataset 'station_time' holds nan at row 1, column 0: finite numbers expected"), std::string::npos)
      << nan;
  // Finding 17: finite but huge snapshots (1e300) overflowed the POD's products into infinities,
  // again a std::invalid_argument. Every dataset is now bounded as it is read.
  {
    Hdf5Writer h5(dir / "huge.h5");
    write_file_format(h5, kSnapshotDatabase);
    h5.attribute("kind", std::string("offline"));
    h5.attribute("case_name", std::string("x"));
    h5.write("B1", std::vector<double>{1e300, 2, 3, 4}, 2, 2);
    h5.commit();
  }
  const std::string huge = error_reading([&] { reduce::reduce_database(dir / "huge.h5", {}); });
  EXPECT_EQ(huge.rfind((dir / "huge.h5").string() + ": dataset 'B1' holds a value of magnitude 1e+300, ", 0), 0u) << huge;
  EXPECT_NE(huge.find("beyond any displacement (mm) or time (s) of a job (|value| <= 1e7)"), std::string::npos) << huge;
  std::filesystem::remove_all(dir);
}

// Finding 26 (docs/robustness.md): a model whose prior mean was 5.5e306 (finite) passed the reader,
// and the predictor's bound on the commanded offset came out infinite. Every number of a model is now
// bounded as it is read, and a prior standard deviation too small to invert is refused.
TEST(LightModel, NumbersPastAnyRealModelAreRefusedAsTheyAreRead) {
  const auto dir = std::filesystem::temp_directory_path() / "drom_huge_model";
  std::filesystem::create_directories(dir);
  reduce::LightModel huge_mean = test::synthetic_model();
  huge_mean.prior_mean = Eigen::VectorXd::Constant(huge_mean.rank(), 1.0);
  huge_mean.prior_mean[0] = 5.53776e306;
  huge_mean.write(dir / "huge_mean.h5");
  const std::string mean = error_reading([&] { reduce::LightModel::read(dir / "huge_mean.h5"); });
  EXPECT_EQ(mean.rfind((dir / "huge_mean.h5").string() + ": dataset 'prior_mean' holds a value of magnitude 5.53776e+306, beyond any length", 0), 0u) << mean;
  EXPECT_NE(mean.find("(|value| <= 1e12)"), std::string::npos) << mean;

  reduce::LightModel tiny_sd = test::synthetic_model();
  tiny_sd.prior_sd[0] = 1e-300;
  tiny_sd.write(dir / "tiny_sd.h5");
  EXPECT_EQ(error_reading([&] { reduce::LightModel::read(dir / "tiny_sd.h5"); }),
            (dir / "tiny_sd.h5").string() + ": prior_sd: standard deviations of at least 1e-30 expected");

  // At the bounds, the model is read.
  reduce::LightModel edge = test::synthetic_model();
  edge.prior_sd[0] = 1e-30;
  edge.prior_mean = Eigen::VectorXd::Constant(edge.rank(), 1e12);
  edge.write(dir / "edge.h5");
  EXPECT_EQ(reduce::LightModel::read(dir / "edge.h5").prior_mean[0], 1e12);
  std::filesystem::remove_all(dir);
}
