// Issue 44, check 1: a run owns its output folder (support/run_folder.hpp). `drom finish` and
// `drom copy` are SIGKILLed at several moments of a rerun into a finished folder: the folder stays the
// earlier run's, byte for byte, and the killed run's files are only in `<out>.partial`, with no
// summary.json; a run that completes leaves exactly its own files. A copy rerun with fewer packets
// leaves no stale packet. And the folder problems are found before the work.
#include "dome_cloud.hpp"
#include "drom_process.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cmath>
#include <csignal>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

namespace fs = std::filesystem;

namespace {

fs::path root() { return fs::temp_directory_path() / ("drom_output_folder_" + std::to_string(::getpid())); }

// Every regular file under `dir`, by relative path, with its bytes.
std::map<std::string, std::string> snapshot(const fs::path& dir) {
  std::map<std::string, std::string> files;
  if (!fs::exists(dir)) return files;
  for (const auto& e : fs::recursive_directory_iterator(dir)) {
    if (!e.is_regular_file()) continue;
    std::ifstream in(e.path(), std::ios::binary);
    files[fs::relative(e.path(), dir).string()] = std::string(std::istreambuf_iterator<char>(in), {});
  }
  return files;
}

std::vector<std::string> words(const std::string& line) {
  std::istringstream in(line);
  std::vector<std::string> w;
  for (std::string s; in >> s;) w.push_back(s);
  return w;
}

// A complete folder: summary.json, and no file beside the ones it lists (and their optimisation cache).
void expect_one_complete_run(const fs::path& out) {
  ASSERT_TRUE(fs::exists(out / "summary.json")) << out;
  const auto summary = nlohmann::json::parse(std::ifstream(out / "summary.json"));
  std::set<std::string> listed = {"summary.json", ".drom_run"};
  for (const auto& f : summary["files"]) listed.insert(f.get<std::string>());
  for (const auto& [name, bytes] : snapshot(out))
    if (!name.starts_with("optimization/")) {
      EXPECT_TRUE(listed.count(name)) << name << " in " << out << " is not in its summary.json";
    }
  for (const auto& name : listed) EXPECT_TRUE(fs::exists(out / name)) << name;
}

// SIGKILL after `delay` seconds unless the process ended before; its exit code, or -signal.
int kill_after(pid_t pid, double delay) {
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(delay);
  int status = 0;
  while (std::chrono::steady_clock::now() < until) {
    if (::waitpid(pid, &status, WNOHANG) == pid) return WIFEXITED(status) ? WEXITSTATUS(status) : -WTERMSIG(status);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  ::kill(pid, SIGKILL);
  return wait_drom(pid);
}

// Reruns `command` into `out` (which holds a finished run) and kills it after each delay. Each time,
// either the kill landed and `out` is byte for byte what it was, with no summary.json in the
// `.partial` folder, or the run had finished and `out` is that one complete run.
void kill_reruns(const std::vector<std::string>& command, const fs::path& out, const std::vector<double>& delays) {
  ASSERT_FALSE(delays.empty());
  const fs::path partial = out.string() + ".partial";
  int landed = 0;
  for (const double delay : delays) {
    const auto before = snapshot(out);
    const int code = kill_after(spawn_drom(command, root() / "killed.log"), delay);
    const auto now = snapshot(out);
    if (code == -SIGKILL && now == before) {
      ++landed;
      EXPECT_FALSE(fs::exists(partial / "summary.json")) << "killed after " << delay << " s";
    } else if (code == -SIGKILL) {
      // Killed after its folder was swapped in (while it deleted the one it replaced, or exited):
      // then the folder is the new run, whole.
      EXPECT_NE(now.at("summary.json"), before.at("summary.json")) << "killed after " << delay << " s: the folder changed, but not to a new run";
    } else {
      EXPECT_EQ(code, 0) << "after " << delay << " s";
    }
    expect_one_complete_run(out);
  }
  EXPECT_GE(landed, 2) << "too few kills landed before the run ended: the delays are too long for this machine";
}

}  // namespace

TEST(OutputFolder, KilledFinishRerunsLeaveTheFinishedFolderAsItWas) {
  fs::create_directories(root());
  const fs::path out = root() / "finish";
  const std::string command = std::string("finish ") + DROM_SOURCE_DIR +
                              "/cases/inclined_plane.toml --set zoning.optimize=true --set zoning.clusters=[2,3] --threads 1 --quiet --out " + out.string();
  ASSERT_EQ(wait_drom(spawn_drom(words(command + " --set zoning.budget=40"), root() / "first.log")), 0);
  expect_one_complete_run(out);
  // The reruns search longer: every file they write differs from the finished run's (K2.json and K3.json
  // are written as each K ends, the rest at the end).
  kill_reruns(words(command + " --set zoning.budget=60"), out, {0.1, 0.3, 0.5, 0.7, 0.9, 1.1, 1.3, 1.6, 2.0, 30});
  fs::remove_all(root());
}

TEST(OutputFolder, KilledCopyRerunsAndFewerPacketsLeaveNoStaleFile) {
  fs::create_directories(root());
  const fs::path cloud = root() / "dome.ply";
  std::ofstream(cloud) << dome_ply();
  const fs::path out = root() / "copy";
  // The seed's hollow cone [10, 80] and every machinable point covered: the vertical misses the dome's
  // top, and two packets are needed.
  const std::string common = "copy " + cloud.string() + " --tool ball:6 --machine ucp710_like --set normals.from_file=true --set visibility.theta_step=10 " +
                             "--set visibility.cone=[10,80] --set packets.coverage=1 --set finishing.step=1 --set finishing.scallop=0.05 --set roughing.depth=5 " +
                             "--set roughing.longitudinal_step=4 --quiet --out " + out.string();
  ASSERT_EQ(wait_drom(spawn_drom(words(common), root() / "first.log")), 0);
  expect_one_complete_run(out);
  ASSERT_TRUE(fs::exists(out / "packet_2")) << "the dome needs two packets or more";
  // The reruns leave a finer scallop: every file they write differs from the finished run's.
  kill_reruns(words(common + " --set finishing.scallop=0.04"), out, {0.1, 0.4, 0.7, 1.0, 1.3, 1.6, 1.9, 2.2, 2.6, 30});
  // Fewer packets: the earlier packet_2 does not survive beside the new run.
  ASSERT_EQ(wait_drom(spawn_drom(words(common + " --set packets.max_packets=1 --set packets.coverage=0.5"), root() / "fewer.log")), 0);
  expect_one_complete_run(out);
  EXPECT_TRUE(fs::exists(out / "packet_1"));
  EXPECT_FALSE(fs::exists(out / "packet_2"));
  EXPECT_FALSE(fs::exists(out.string() + ".partial"));
  fs::remove_all(root());
}

TEST(OutputFolder, AFolderDromDidNotWriteIsNeverReplaced) {
  fs::create_directories(root());
  const fs::path mine = root() / "my_project";
  fs::create_directories(mine);
  std::ofstream(mine / "notes.txt") << "my own file\n";
  const fs::path program = mine / "p.ngc";
  std::ofstream(program) << "G21 G90\nG0 X0 Y0 Z5\nG1 X10 F500\nM30\n";
  std::ofstream(root() / "elsewhere.ngc") << "G21 G90\nG0 X0 Y0 Z5\nG1 X10 F500\nM30\n";
  // A folder of the user's files (however it is spelled), one holding the run's input, the current
  // folder: refused, and nothing in them touched.
  for (const std::string& out : {mine.string(), mine.string() + "/", mine.string() + "/."}) {
    const DromResult r = run_drom("machine " + (root() / "elsewhere.ngc").string() + " --out " + out);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("a folder of files drom did not write"), std::string::npos) << r.output;
  }
  const DromResult input_inside = run_drom("machine " + program.string() + " --out " + mine.string());
  EXPECT_EQ(input_inside.exit_code, 2) << input_inside.output;
  EXPECT_TRUE(fs::exists(mine / "notes.txt"));
  EXPECT_TRUE(fs::exists(program));
  const auto here = fs::current_path();
  fs::current_path(mine);
  const DromResult dot = run_drom("machine " + (root() / "elsewhere.ngc").string() + " --out .");
  fs::current_path(here);
  EXPECT_EQ(dot.exit_code, 2) << dot.output;
  EXPECT_NE(dot.output.find("the current folder lies in it"), std::string::npos) << dot.output;
  EXPECT_TRUE(fs::exists(mine / "notes.txt"));
  // An empty folder, or one a drom run wrote, is the run's.
  fs::create_directories(root() / "empty");
  EXPECT_EQ(run_drom("machine " + (root() / "elsewhere.ngc").string() + " --out " + (root() / "empty").string()).exit_code, 0);
  EXPECT_EQ(run_drom("machine " + (root() / "elsewhere.ngc").string() + " --out " + (root() / "empty").string()).exit_code, 0);
  fs::remove_all(root());
}

TEST(OutputFolder, AnOutputThatCannotBeAFolderIsRefusedBeforeTheWork) {
  fs::create_directories(root());
  const fs::path file = root() / "a_file";
  std::ofstream(file) << "not a folder\n";
  const std::string finish = std::string("finish ") + DROM_SOURCE_DIR + "/cases/inclined_plane.toml --quiet --out ";
  const std::string talkative = std::string("finish ") + DROM_SOURCE_DIR + "/cases/inclined_plane.toml --out ";
  for (const fs::path& out : {file, file / "below"}) {
    const DromResult r = run_drom(talkative + out.string());
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("--out " + out.string()), std::string::npos) << r.output;
    EXPECT_EQ(r.output.find("verdict"), std::string::npos) << "found only after the work: " << r.output;
  }
  // A misspelled machine is refused before the work too, with exit 2.
  const DromResult machine = run_drom(finish + (root() / "m").string() + " --set machine.definition=ucp710_lik");
  EXPECT_EQ(machine.exit_code, 2) << machine.output;
  EXPECT_NE(machine.output.find("ucp710_lik"), std::string::npos) << machine.output;
  EXPECT_FALSE(fs::exists(root() / "m"));
  fs::remove_all(root());
}
