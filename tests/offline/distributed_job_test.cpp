// Issue 26 checks: the offline job over MPI ranks (mpirun -np 2 --oversubscribe) and in slices
// (--stations a:b, then drom merge) writes the serial run's database byte for byte; a rank killed
// mid-run loses no finished station and the rerun with another rank count writes the same bytes; a
// bad case stops every rank with the same error and exit code 2, within seconds.
#include "drom_process.hpp"

#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <sstream>
#include <string>
#include <thread>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace {

namespace fs = std::filesystem;

// The coarse flat plate of tests/offline/offline_job_test.cpp (100 mm elements, 1 mm voxels), with a
// station every 900 mm of cut (33 stations) to keep the suite short.
const std::string kPlate =
    " --set mesh.nx=10 --set mesh.ny=10 --set path.station_spacing=900 --set removal.voxel_size=1.0"
    " --set clamps.0.box=[0,100,0,100] --set clamps.1.box=[900,1000,0,100] --set clamps.2.box=[0,100,900,1000] --set clamps.3.box=[900,1000,900,1000]";

fs::path dir(const std::string& name) {
  const auto d = fs::temp_directory_path() / "drom_distributed_tests" / name;
  fs::remove_all(d);
  return d;
}

std::string bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// "" on success, otherwise the exit code and what drom said.
std::string run(const std::string& args) {
  const DromResult r = run_drom(args + " --quiet");
  return r.exit_code == 0 ? "" : "exit " + std::to_string(r.exit_code) + ": " + r.output;
}

// The serial database of a job (in a folder of the test's own: ctest runs tests side by side).
std::string serial_database(const std::string& command) {
  const auto out = dir(std::string("serial_") + ::testing::UnitTest::GetInstance()->current_test_info()->name() + "_" + command);
  EXPECT_EQ(run(command + kPlate + " --threads 2 --out " + out.string()), "");
  return bytes(out / "database.h5");
}

std::size_t station_files(const fs::path& out) {
  std::size_t n = 0;
  std::error_code error;
  for (const auto& e : fs::directory_iterator(out / ".checkpoint", error)) n += e.path().filename().string().rfind("station_", 0) == 0;
  return n;
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// Runs a shell command line; its exit code and output (stdout and stderr).
DromResult shell(const std::string& command) {
  FILE* pipe = popen((command + " 2>&1").c_str(), "r");
  std::string out;
  std::array<char, 4096> buf;
  while (std::fgets(buf.data(), buf.size(), pipe)) out += buf.data();
  const int status = pclose(pipe);
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, out};
}

#ifdef DROM_MPIEXEC
// mpirun as root refuses to start unless told (docs/distributed.md); the tests may run as root.
const std::string kMpirun = "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 " + std::string(DROM_MPIEXEC) + " --oversubscribe -np ";

DromResult mpirun(int ranks, const std::string& args) { return shell(kMpirun + std::to_string(ranks) + " " + DROM_BINARY + " " + args); }

// The pid of the process that mpirun (`launcher`) started as this rank, or 0.
pid_t rank_pid(pid_t launcher, int rank) {
  for (const auto& e : fs::directory_iterator("/proc")) {
    const std::string name = e.path().filename().string();
    if (name.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream stat(e.path() / "stat");
    std::string pid, comm, state;
    long parent = 0;
    if (!(stat >> pid >> comm >> state >> parent) || parent != launcher) continue;
    std::ifstream env(e.path() / "environ", std::ios::binary);
    const std::string vars((std::istreambuf_iterator<char>(env)), {});
    if (vars.find(std::string("OMPI_COMM_WORLD_RANK=") + std::to_string(rank) + '\0') != std::string::npos) return static_cast<pid_t>(std::stol(name));
  }
  return 0;
}

void two_ranks_write_the_serial_bytes(const std::string& command) {
  const auto out = dir("two_ranks_" + command);
  const auto r = mpirun(2, command + kPlate + " --threads 1 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  // Rank 0 alone reports and writes: one summary line, one progress stream.
  EXPECT_EQ(count(r.output, "-> " + out.string() + "/database.h5"), 1u) << r.output;
  EXPECT_EQ(count(r.output, "station 33/33"), 1u) << r.output;
  EXPECT_TRUE(bytes(out / "database.h5") == serial_database(command)) << command;
  EXPECT_FALSE(fs::exists(out / ".checkpoint"));
}

TEST(Distributed, TwoRanksWriteTheSerialDatabaseByteForByte) { two_ranks_write_the_serial_bytes("offline"); }

// The same for drom truth, and drom run's offline-and-truth pass (slow: ctest -L slow).
TEST(SlowDistributed, TruthAndRunOnTwoRanksWriteTheSerialDatabases) {
  two_ranks_write_the_serial_bytes("truth");
  const auto serial = dir("run_serial"), ranks = dir("run_ranks");
  ASSERT_EQ(run("run" + kPlate + " --threads 2 --out " + serial.string()), "");
  const auto r = mpirun(2, "run" + kPlate + " --quiet --threads 1 --out " + ranks.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  for (const char* stage : {"offline", "truth"})
    EXPECT_TRUE(bytes(serial / stage / "database.h5") == bytes(ranks / stage / "database.h5")) << stage;
  EXPECT_TRUE(fs::exists(ranks / "summary.json"));
}

TEST(Distributed, KilledRankLeavesItsStationsAndTheRerunWithOtherRanksWritesTheSameBytes) {
  const auto out = dir("killed");
  // Two ranks of one thread; rank 1 is killed (SIGKILL) once the first stations are on disk.
  const pid_t launcher = fork();
  ASSERT_GE(launcher, 0);
  if (launcher == 0) {
    setenv("OMPI_ALLOW_RUN_AS_ROOT", "1", 1);
    setenv("OMPI_ALLOW_RUN_AS_ROOT_CONFIRM", "1", 1);
    const std::string out_arg = out.string();
    std::vector<std::string> args = {DROM_MPIEXEC, "--oversubscribe", "-np", "2", DROM_BINARY, "offline", "--quiet", "--threads", "1", "--out", out_arg};
    std::istringstream plate(kPlate);
    for (std::string word; plate >> word;) args.push_back(word);
    std::vector<char*> argv;
    for (auto& a : args) argv.push_back(a.data());
    argv.push_back(nullptr);
    freopen("/dev/null", "w", stdout);
    freopen("/dev/null", "w", stderr);
    execvp(argv[0], argv.data());
    _exit(127);
  }
  const auto start = std::chrono::steady_clock::now();
  pid_t victim = 0;
  while (station_files(out) < 2 && std::chrono::steady_clock::now() - start < std::chrono::seconds(120))
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  victim = rank_pid(launcher, 1);
  ASSERT_GT(victim, 0) << "rank 1 not found among mpirun's children";
  ASSERT_EQ(kill(victim, SIGKILL), 0);
  int status = 0;
  waitpid(launcher, &status, 0);
  EXPECT_FALSE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "mpirun should report the killed rank";
  const std::size_t left = station_files(out);
  std::printf("killed rank 1 with %zu stations on disk\n", left);
  EXPECT_GE(left, 2u);
  ASSERT_FALSE(fs::exists(out / "database.h5")) << "the job finished before the kill: nothing was tested";
  // The rerun, as one process (another N), does only what is missing.
  const DromResult resumed = run_drom("offline" + kPlate + " --threads 1 --resume --out " + out.string());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_TRUE(bytes(out / "database.h5") == serial_database("offline"));
}

TEST(Distributed, BadInputStopsEveryRankWithTheSameErrorAndExitCode2) {
  const auto out = dir("bad_case");
  fs::create_directories(out);
  const auto bad = out / "bad.toml";
  {
    std::string text = bytes(fs::path(DROM_SOURCE_DIR) / "cases" / "flat_plate.toml");
    text.replace(text.find("nz = 5"), 6, "nz = 5\nsurprise = 3");
    std::ofstream(bad) << text;
  }
  const auto start = std::chrono::steady_clock::now();
  const auto r = mpirun(2, "offline " + bad.string() + " --out " + out.string());
  const double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_LT(seconds, 30.0);
  // Both ranks say the same (the file and the key), no "rank" prefix: they all failed alike.
  EXPECT_EQ(count(r.output, "drom offline: error: "), 2u) << r.output;
  EXPECT_EQ(count(r.output, "surprise"), 2u) << r.output;
  EXPECT_EQ(count(r.output, "bad.toml"), 2u) << r.output;

  // Input that only rank 0 sees as bad (the checkpoint of another case in --out): rank 1 stops too,
  // and both say rank 0's message, prefixed with where it failed.
  ASSERT_EQ(run("offline" + kPlate + " --stop-after 1 --threads 1 --out " + out.string()), "");
  const auto other = mpirun(2, "offline" + kPlate + " --set stress.sigma11=[1,2,3] --resume --quiet --out " + out.string());
  EXPECT_EQ(other.exit_code, 2) << other.output;
  EXPECT_EQ(count(other.output, "different case"), 2u) << other.output;
  EXPECT_EQ(count(other.output, "rank 0 of 2"), 2u) << other.output;  // the same message names where it failed
}
#else
TEST(Distributed, WithoutMpiDromRefusesToRunAsOneOfSeveralRanks) {
  const auto out = dir("no_mpi");
  const DromResult r = shell("OMPI_COMM_WORLD_SIZE=2 OMPI_COMM_WORLD_RANK=1 " + std::string(DROM_BINARY) + " offline" + kPlate + " --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("built without MPI"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out / ".checkpoint"));
}
#endif

TEST(Distributed, ThreeSlicesMergedWriteTheSerialDatabaseByteForByte) {
  const auto out = dir("slices");
  ASSERT_EQ(run("offline" + kPlate + " --threads 1 --stations 0:4 --out " + out.string()), "");
  ASSERT_EQ(run("offline" + kPlate + " --threads 1 --stations 9: --out " + out.string()), "");
  EXPECT_FALSE(fs::exists(out / "database.h5"));
  // A missing slice is named, and refused.
  const auto early = run_drom("merge" + kPlate + " --out " + out.string());
  EXPECT_EQ(early.exit_code, 2) << early.output;
  EXPECT_NE(early.output.find("stations 4:9"), std::string::npos) << early.output;
  ASSERT_EQ(run("offline" + kPlate + " --threads 1 --stations 4:9 --out " + out.string()), "");
  // A slice of another job is named, and refused.
  const auto stranger = dir("slices_stranger");
  ASSERT_EQ(run("offline" + kPlate + " --set stress.sigma11=[1,2,3] --threads 1 --stations 5:6 --out " + stranger.string()), "");
  const auto mine = out / ".checkpoint" / "station_00005.bin";
  const std::string kept = bytes(mine);
  fs::copy_file(stranger / ".checkpoint" / "station_00005.bin", mine, fs::copy_options::overwrite_existing);
  const auto mixed = run_drom("merge" + kPlate + " --out " + out.string());
  EXPECT_EQ(mixed.exit_code, 2) << mixed.output;
  EXPECT_NE(mixed.output.find("station_00005.bin: written by another job (slice 4:9"), std::string::npos) << mixed.output;
  std::ofstream(mine, std::ios::binary) << kept;
  // A slice of the wrong range is refused before any work.
  EXPECT_NE(run("offline" + kPlate + " --stations 9:4 --out " + out.string()).find("a:b needs 0 <= a < b"), std::string::npos);
  ASSERT_EQ(run("merge" + kPlate + " --out " + out.string()), "");
  EXPECT_TRUE(bytes(out / "database.h5") == serial_database("offline"));
}

}  // namespace
