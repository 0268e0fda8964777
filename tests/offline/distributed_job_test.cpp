// Issue 26 checks: the offline job over MPI ranks (mpirun -np 2 --oversubscribe) and in slices
// (--stations a:b, then drom merge) writes the serial run's database byte for byte; a rank killed
// mid-run loses no finished station and the rerun with another rank count writes the same bytes; a
// bad case stops every rank with the same error and exit code 2, within seconds. drom_solo (drom
// linked without MPI, apps/CMakeLists.txt) computes slices, merges, and refuses to be one of
// several ranks. Every check compares with one serial run, DistributedReference.SerialRun (a ctest
// fixture: it runs first, once).
#include "drom_process.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <thread>
#include <sys/wait.h>
#include <unistd.h>
#include <vector>

namespace {

namespace fs = std::filesystem;

// The coarse flat plate at its coarsest: 5 x 5 x 5 Hex20 (200 mm elements: the pocket's walls at
// 200 and 800 mm and its floor at 8 mm stay on element faces), 2 mm voxels, a station every 900 mm
// of cut: 33 stations, enough to split three ways and between ranks, a few hundredths of a second each.
// Chunks of 4 stations: the killed rank's test needs rank 1 to own several chunks ("auto" takes all 33
// stations in one chunk on this little mesh); the truth test runs "auto".
const std::string kPlate =
    " --set mesh.nx=5 --set mesh.ny=5 --set path.station_spacing=900 --set removal.voxel_size=2.0"
    " --set clamps.0.box=[0,100,0,100] --set clamps.1.box=[900,1000,0,100] --set clamps.2.box=[0,100,900,1000] --set clamps.3.box=[900,1000,900,1000]"
    " --set solver.stations_per_factorization=4";
constexpr std::size_t kStations = 33;

// This build's scratch folder (ctest runs tests side by side, and other builds may run theirs).
fs::path dir(const std::string& name) {
  const auto d = fs::path(DROM_TEST_SCRATCH) / name;
  fs::remove_all(d);
  return d;
}

std::string bytes(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), {}};
}

// "" on success, otherwise the exit code and what drom said.
std::string run(const std::string& args, const std::string& binary = DROM_BINARY) {
  const DromResult r = run_drom(args + " --quiet", binary);
  return r.exit_code == 0 ? "" : "exit " + std::to_string(r.exit_code) + ": " + r.output;
}

// The serial run's database: DistributedReference.SerialRun's (made again here when a test runs
// without it, outside ctest).
const fs::path kReference = fs::path(DROM_TEST_SCRATCH) / "reference";
std::string serial_offline_database() {
  if (!fs::exists(kReference / "database.h5")) {
    EXPECT_EQ(run("offline" + kPlate + " --threads 1 --out " + dir("reference").string()), "");
  }
  return bytes(kReference / "database.h5");
}

nlohmann::json summary(const fs::path& out) {
  std::ifstream in(out / "summary.json");
  return nlohmann::json::parse(in);
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

TEST(DistributedReference, SerialRun) {
  const auto out = dir("reference");
  ASSERT_EQ(run("offline" + kPlate + " --threads 1 --out " + out.string()), "");
  const auto s = summary(out);
  EXPECT_EQ(s["stations"].get<std::size_t>(), kStations);
  EXPECT_EQ(s["ranks"].get<int>(), 1);
  EXPECT_EQ(s["deal_measured_stations"].get<std::size_t>(), 0u);  // a fresh job: the cost law alone
}

#ifdef DROM_MPIEXEC
// The station files in out's checkpoint folder, of stations `first` and after.
std::size_t station_files(const fs::path& out, std::size_t first = 0) {
  std::size_t n = 0;
  std::error_code error;
  for (const auto& e : fs::directory_iterator(out / ".checkpoint", error)) {
    const std::string name = e.path().filename().string();
    n += name.rfind("station_", 0) == 0 && std::stoul(name.substr(8, 5)) >= first;
  }
  return n;
}

std::size_t count(const std::string& text, const std::string& what) {
  std::size_t n = 0;
  for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
  return n;
}

// mpirun as root refuses to start unless told (docs/distributed.md); the tests may run as root.
const std::string kMpirun = "OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 " + std::string(DROM_MPIEXEC) + " --oversubscribe -np ";

DromResult mpirun(int ranks, const std::string& args, const std::string& binary = DROM_BINARY) {
  return shell(kMpirun + std::to_string(ranks) + " " + binary + " " + args);
}

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

// `command` on two ranks of one thread: rank 0 alone reports and writes, and its database is
// `serial`'s bytes.
void two_ranks_write_the_serial_bytes(const std::string& command, const std::string& serial, const std::string& extra = "") {
  const auto out = dir("two_ranks_" + command);
  const auto r = mpirun(2, command + kPlate + extra + " --threads 1 --out " + out.string());
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(count(r.output, "-> " + out.string() + "/database.h5"), 1u) << r.output;
  const std::string last = "station " + std::to_string(kStations) + "/" + std::to_string(kStations);
  EXPECT_EQ(count(r.output, last), 1u) << r.output;
  EXPECT_TRUE(bytes(out / "database.h5") == serial) << command;
  EXPECT_EQ(summary(out)["ranks"].get<int>(), 2);
  EXPECT_FALSE(fs::exists(out / ".checkpoint"));
}

TEST(Distributed, TwoRanksWriteTheSerialDatabaseByteForByte) { two_ranks_write_the_serial_bytes("offline", serial_offline_database()); }

// The same for drom truth (its serial run here: one profile, cheap), with the chunk chosen by each
// rank from the history ("auto"): every rank chooses the same,
TEST(Distributed, TwoRanksWriteTheSerialTruthDatabaseByteForByte) {
  const auto truth = dir("truth_serial");
  const std::string automatic = " --set solver.stations_per_factorization=auto";
  ASSERT_EQ(run("truth" + kPlate + automatic + " --threads 1 --out " + truth.string()), "");
  EXPECT_TRUE(summary(truth)["chunk_plan"]["chosen"].get<bool>());
  EXPECT_GT(summary(truth)["chunk_plan"]["stations_per_factorization"].get<int>(), 4);
  two_ranks_write_the_serial_bytes("truth", bytes(truth / "database.h5"), automatic);
}

// and for drom run's offline-and-truth pass (slow, ctest -L slow: the loop after the pass, on rank 0,
// is most of its 40 s).
TEST(SlowDistributed, RunOnTwoRanksWritesTheSerialDatabases) {
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
  // Two ranks of one thread; rank 1 is stopped (SIGSTOP) as soon as it has saved a station, so the
  // job cannot finish meanwhile, then killed (SIGKILL). A fresh job's blocks follow the cost law, which
  // never rises along the job: rank 0's block holds at most half the stations (rounded up), so the
  // stations after those are rank 1's.
  const std::size_t rank1_from = kStations / 2 + 1;
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
  auto waiting = [&] { return std::chrono::steady_clock::now() - start < std::chrono::seconds(120); };
  pid_t victim = 0;
  while (!(victim = rank_pid(launcher, 1)) && waiting()) std::this_thread::sleep_for(std::chrono::milliseconds(5));
  ASSERT_GT(victim, 0) << "rank 1 not found among mpirun's children";
  while (station_files(out, rank1_from) < 1 && waiting()) std::this_thread::sleep_for(std::chrono::milliseconds(2));
  ASSERT_EQ(kill(victim, SIGSTOP), 0);
  const std::size_t left = station_files(out), rank1_left = station_files(out, rank1_from);
  const bool finished_before = fs::exists(out / "database.h5");
  ASSERT_EQ(kill(victim, SIGKILL), 0);
  int status = 0;
  waitpid(launcher, &status, 0);
  ASSERT_FALSE(finished_before) << "the job finished before the kill: nothing was tested";
  EXPECT_FALSE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "mpirun should report the killed rank";
  const std::size_t kept = station_files(out);
  std::printf("killed rank 1 with %zu stations on disk, %zu of them rank 1's (%zu after rank 0 stopped)\n", left, rank1_left, kept);
  EXPECT_GE(rank1_left, 1u);
  EXPECT_EQ(station_files(out, rank1_from), rank1_left);  // the killed rank's finished stations are kept
  EXPECT_LT(kept, kStations);
  EXPECT_FALSE(fs::exists(out / "database.h5"));
  // The rerun, as one process (another N), does only what is missing; the stations on disk carry
  // their measured solve times, which weight the deal.
  const DromResult resumed = run_drom("offline" + kPlate + " --threads 1 --resume --out " + out.string());
  ASSERT_EQ(resumed.exit_code, 0) << resumed.output;
  EXPECT_TRUE(bytes(out / "database.h5") == serial_offline_database());
  EXPECT_EQ(summary(out)["deal_measured_stations"].get<std::size_t>(), kept);
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
  std::printf("mpirun -np 2 with a bad case: exit %d after %.1f s\n", r.exit_code, seconds);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_LT(seconds, 30.0);
  // Both ranks say the same (the file and the key), no "rank" prefix: they all failed alike.
  EXPECT_EQ(count(r.output, "drom offline: error: "), 2u) << r.output;
  EXPECT_EQ(count(r.output, "surprise"), 2u) << r.output;
  EXPECT_EQ(count(r.output, "bad.toml"), 2u) << r.output;

  // Input that only rank 0 sees as bad (the unfinished job of another case in --out, left by a
  // slice): rank 1 stops too, and both say rank 0's message, prefixed with where it failed.
  ASSERT_EQ(run("offline" + kPlate + " --stations 0:1 --threads 1 --out " + out.string()), "");
  const auto other = mpirun(2, "offline" + kPlate + " --set stress.sigma11=[1,2,3] --resume --quiet --out " + out.string());
  EXPECT_EQ(other.exit_code, 2) << other.output;
  EXPECT_EQ(count(other.output, "different case"), 2u) << other.output;
  EXPECT_EQ(count(other.output, "rank 0 of 2"), 2u) << other.output;  // the same message names where it failed
}

// drom linked without MPI, started by mpirun as two ranks: both refuse, exit 2, before any work.
TEST(Distributed, WithoutMpiDromRefusesToRunAsOneOfSeveralRanks) {
  const auto out = dir("no_mpi");
  const auto r = mpirun(2, "offline" + kPlate + " --out " + out.string(), DROM_SOLO_BINARY);
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_EQ(count(r.output, "built without MPI"), 2u) << r.output;
  EXPECT_NE(r.output.find("as rank 1 of 2"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out / ".checkpoint"));
}
#else
// A build without MPI has no mpirun to test with: the launcher's environment, as mpirun sets it.
TEST(Distributed, WithoutMpiDromRefusesToRunAsOneOfSeveralRanks) {
  const auto out = dir("no_mpi");
  const DromResult r = shell("OMPI_COMM_WORLD_SIZE=2 OMPI_COMM_WORLD_RANK=1 " + std::string(DROM_SOLO_BINARY) + " offline" + kPlate + " --out " + out.string());
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("built without MPI"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out / ".checkpoint"));
}
#endif

// Slices by drom and by drom_solo (no MPI) into one folder, merged by drom_solo.
TEST(Distributed, ThreeSlicesMergedWriteTheSerialDatabaseByteForByte) {
  const auto out = dir("slices");
  ASSERT_EQ(run("offline" + kPlate + " --threads 1 --stations 0:4 --out " + out.string()), "");
  ASSERT_EQ(run("offline" + kPlate + " --threads 1 --stations 9: --out " + out.string(), DROM_SOLO_BINARY), "");
  EXPECT_FALSE(fs::exists(out / "database.h5"));
  // A missing slice is named, and refused.
  const auto early = run_drom("merge" + kPlate + " --out " + out.string(), DROM_SOLO_BINARY);
  EXPECT_EQ(early.exit_code, 2) << early.output;
  EXPECT_NE(early.output.find("stations 4:9"), std::string::npos) << early.output;
  ASSERT_EQ(run("offline" + kPlate + " --threads 1 --stations 4:9 --out " + out.string()), "");
  // A slice of another job is named, and refused.
  const auto stranger = dir("slices_stranger");
  ASSERT_EQ(run("offline" + kPlate + " --set stress.sigma11=[1,2,3] --threads 1 --stations 5:6 --out " + stranger.string()), "");
  const auto mine = out / ".checkpoint" / "station_00005.bin";
  const std::string kept = bytes(mine);
  fs::copy_file(stranger / ".checkpoint" / "station_00005.bin", mine, fs::copy_options::overwrite_existing);
  const auto mixed = run_drom("merge" + kPlate + " --out " + out.string(), DROM_SOLO_BINARY);
  EXPECT_EQ(mixed.exit_code, 2) << mixed.output;
  EXPECT_NE(mixed.output.find("station_00005.bin: written by another job (slice 4:9"), std::string::npos) << mixed.output;
  std::ofstream(mine, std::ios::binary) << kept;
  // A slice of the wrong range is refused before any work.
  EXPECT_NE(run("offline" + kPlate + " --stations 9:4 --out " + out.string()).find("a:b needs 0 <= a < b"), std::string::npos);
  ASSERT_EQ(run("merge" + kPlate + " --out " + out.string(), DROM_SOLO_BINARY), "");
  EXPECT_TRUE(bytes(out / "database.h5") == serial_offline_database());
  EXPECT_EQ(summary(out)["deal_measured_stations"].get<std::size_t>(), kStations);  // every station was measured
}

}  // namespace
