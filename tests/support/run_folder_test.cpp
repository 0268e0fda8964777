// A run's output folder (support/run_folder.hpp): the staging folder swapped in whole, nothing of the
// earlier run left beside the new one, a run that never commits leaving the finished folder as it was,
// --resume taking up a killed run's folder or reusing only the entries named, and the folder's problems
// (a file in the way, another writer) found when the run starts.
#include "support/input_error.hpp"
#include "support/run_folder.hpp"

#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <iterator>
#include <string>

#include <unistd.h>

namespace fs = std::filesystem;
using drom::RunFolder;

namespace {

fs::path scratch() {
  const fs::path p = fs::temp_directory_path() / ("drom_run_folder_" + std::to_string(::getpid()));
  fs::create_directories(p);
  return p;
}

void put(const fs::path& p, const std::string& text) {
  fs::create_directories(p.parent_path());
  std::ofstream(p) << text;
}

std::string text(const fs::path& p) {
  std::ifstream in(p);
  return {std::istreambuf_iterator<char>(in), {}};
}

}  // namespace

TEST(RunFolder, ACommittedRunReplacesTheWholeFolderAndAnUncommittedOneChangesNothing) {
  const fs::path out = scratch() / "a" / "out";
  {
    RunFolder first(out);
    EXPECT_EQ(first.staging(), fs::absolute(out).lexically_normal().string() + ".partial");
    put(first.staging() / "summary.json", "first\n");
    put(first.staging() / "packet_2" / "program.ngc", "M30\n");
    first.commit();
  }
  EXPECT_EQ(text(out / "summary.json"), "first\n");
  EXPECT_FALSE(fs::exists(out.string() + ".partial"));
  {
    RunFolder killed(out);  // never commits, as a run killed midway
    put(killed.staging() / "zones.vtu", "half\n");
  }
  EXPECT_EQ(text(out / "summary.json"), "first\n");
  EXPECT_FALSE(fs::exists(out / "zones.vtu"));
  EXPECT_TRUE(fs::exists(out.string() + ".partial/zones.vtu"));
  {
    RunFolder second(out);  // a fresh run clears the killed run's folder
    EXPECT_FALSE(fs::exists(second.staging() / "zones.vtu"));
    put(second.staging() / "summary.json", "second\n");
    second.commit();
  }
  EXPECT_EQ(text(out / "summary.json"), "second\n");
  EXPECT_FALSE(fs::exists(out / "packet_2"));  // nothing of the earlier run beside the new one
  for (const auto& e : fs::directory_iterator(out.parent_path())) {
    const std::string name = e.path().filename().string();
    EXPECT_TRUE(name == "out" || name == ".out.lock") << name;
  }
  fs::remove_all(scratch());
}

TEST(RunFolder, ResumeTakesUpAKilledRunOrReusesOnlyTheNamedEntries) {
  const fs::path out = scratch() / "out";
  {
    RunFolder done(out);
    put(done.staging() / "optimization" / "K2.json", "k2\n");
    put(done.staging() / "summary.json", "done\n");
    done.commit();
  }
  {
    RunFolder resumed(out, {.resume = true, .reused = {"optimization", "missing"}, .inputs = {}});
    EXPECT_FALSE(resumed.resumed_partial());
    EXPECT_EQ(text(resumed.staging() / "optimization" / "K2.json"), "k2\n");
    EXPECT_FALSE(fs::exists(resumed.staging() / "summary.json"));
    EXPECT_EQ(fs::hard_link_count(resumed.staging() / "optimization" / "K2.json"), 2u);  // linked, not copied
    put(resumed.staging() / "optimization" / "K3.json", "k3\n");  // then killed
  }
  {
    RunFolder again(out, {.resume = true, .reused = {"optimization"}, .inputs = {}});
    EXPECT_TRUE(again.resumed_partial());
    EXPECT_EQ(text(again.staging() / "optimization" / "K3.json"), "k3\n");
    again.commit();
  }
  EXPECT_TRUE(fs::exists(out / "optimization" / "K3.json"));
  EXPECT_FALSE(fs::exists(out / "summary.json"));
  fs::remove_all(scratch());
}

TEST(RunFolder, AFileInTheWayOrAnotherWriterIsAnErrorAtTheStart) {
  const fs::path file = scratch() / "file";
  put(file, "x\n");
  for (const fs::path& out : {file, file / "below"}) {
    try {
      RunFolder f(out);
      ADD_FAILURE() << out;
    } catch (const drom::InputError& e) {
      EXPECT_NE(std::string(e.what()).find("--out " + out.string()), std::string::npos) << e.what();
    }
  }
  const fs::path out = scratch() / "busy";
  RunFolder first(out);
  try {
    RunFolder second(out);
    ADD_FAILURE() << "two runs writing one folder";
  } catch (const drom::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("another drom is writing this folder"), std::string::npos) << e.what();
  }
  EXPECT_THROW(RunFolder("/"), drom::InputError);
  fs::remove_all(scratch());
}
