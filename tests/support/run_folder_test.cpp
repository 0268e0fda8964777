// A run's output folder (support/run_folder.hpp): the staging folder swapped in whole, nothing of the
// earlier run left beside the new one, a run that never commits leaving the finished folder as it was,
// --resume taking up a killed run's folder or reusing only the entries named, and the folder's problems
// (a file in the way, another writer) found when the run starts.
#include "support/input_error.hpp"
#include "support/run_folder.hpp"
#include "support/summary.hpp"

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
    put(resumed.staging() / "optimization" / "K3.json", "k3\n");
    put(resumed.staging() / "program.ngc", "refused now\n");  // then killed
    put(resumed.staging() / "packet_2" / "finishing.ngc", "stale\n");
  }
  {
    RunFolder again(out, {.resume = true, .reused = {"optimization"}, .inputs = {}});
    EXPECT_TRUE(again.resumed_partial());
    EXPECT_EQ(text(again.staging() / "optimization" / "K3.json"), "k3\n");
    // What the killed run wrote outside the reused entries is not taken over.
    EXPECT_FALSE(fs::exists(again.staging() / "program.ngc"));
    EXPECT_FALSE(fs::exists(again.staging() / "packet_2"));
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

// The distortion chain's commands write straight into their folder: a new run clears the earlier
// run's summary.json first, then the files it lists, and nothing else; another command's folder, or
// one whose summary.json drom did not write, is refused before anything is removed.
TEST(EarlierRun, ItsSummaryGoesFirstThenTheFilesItListsAndNothingElse) {
  const fs::path out = scratch() / "chain";
  put(out / "summary.json", R"({"command": "run", "files": ["passes.csv", "frames/", "../outside.txt", "/etc/hostname", ".", "a/..", "linked/", "summary.json"]})");
  put(out / "passes.csv", "old\n");
  put(out / "frames" / "station_00001.vtu", "old\n");
  put(out / "offline" / "database.h5", "a cache under its own key\n");
  put(out / "notes.txt", "the user's\n");
  put(scratch() / "outside.txt", "not the run's folder\n");
  put(scratch() / "elsewhere" / "keep.txt", "behind a link\n");
  fs::create_directory_symlink(scratch() / "elsewhere", out / "linked");
  drom::clear_earlier_run(out, "run");
  EXPECT_FALSE(fs::exists(out / "summary.json"));
  EXPECT_FALSE(fs::exists(out / "passes.csv"));
  EXPECT_FALSE(fs::exists(out / "frames"));
  EXPECT_FALSE(fs::exists(fs::symlink_status(out / "linked")));             // the link goes,
  EXPECT_TRUE(fs::exists(scratch() / "elsewhere" / "keep.txt"));            // not what it points to
  EXPECT_TRUE(fs::exists(out / "offline" / "database.h5"));                 // "." and "a/.." cleared nothing
  EXPECT_TRUE(fs::exists(out / "notes.txt"));
  EXPECT_TRUE(fs::exists(scratch() / "outside.txt"));
  // Another command's folder, or a summary.json drom did not write: refused, nothing removed.
  put(out / "summary.json", R"({"command": "offline", "files": ["notes.txt"]})");
  try {
    drom::clear_earlier_run(out, "reduce");
    ADD_FAILURE() << "another command's folder cleared";
  } catch (const drom::InputError& e) {
    EXPECT_NE(std::string(e.what()).find("--out " + out.string() + ": it holds the outputs of drom offline"), std::string::npos) << e.what();
  }
  put(out / "summary.json", R"({"files": ["notes.txt"]})");
  EXPECT_THROW(drom::clear_earlier_run(out, "run"), drom::InputError);
  EXPECT_TRUE(fs::exists(out / "summary.json"));
  EXPECT_TRUE(fs::exists(out / "notes.txt"));
  drom::clear_earlier_run(scratch() / "nothing_here", "run");  // no folder: nothing to do
  fs::remove_all(scratch());
}
