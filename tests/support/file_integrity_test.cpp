// The seal on drom's HDF5 files (support/file_integrity.hpp): every truncation, appended byte, flipped
// bit or foreign file is refused by Hdf5Reader before libhdf5 reads it, naming the file and the bytes;
// and atomic writes leave nothing of a writer that died.
#include "support/atomic_file.hpp"
#include "support/file_integrity.hpp"
#include "support/hdf5_reader.hpp"
#include "support/hdf5_writer.hpp"
#include "support/input_error.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <csignal>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <random>
#include <string>

#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

using namespace drom;

namespace {

std::filesystem::path fresh_dir(const std::string& name) {
  const auto dir = std::filesystem::temp_directory_path() / ("drom_" + name + "_" + std::to_string(::getpid()));
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir;
}

std::string bytes_of(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return {std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>()};
}

void put_bytes(const std::filesystem::path& p, const std::string& bytes) { std::ofstream(p, std::ios::binary) << bytes; }

// The message of the InputError that reading `p` throws ("" if none).
std::string refusal(const std::filesystem::path& p) {
  try {
    const Hdf5Reader h5(p);
    h5.matrix("values");
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

// A sealed file of about 160 kB, more than the 64 KiB the seal reads at a time (a segment straddles
// two reads): a matrix and an attribute.
std::filesystem::path sealed_file(const std::filesystem::path& dir) {
  std::vector<double> v(20000);
  for (std::size_t i = 0; i < v.size(); ++i) v[i] = std::sin(0.01 * static_cast<double>(i));
  Hdf5Writer h5(dir / "sealed.h5");
  h5.write("values", v, 400, 50);
  h5.attribute("note", std::string("a sealed file"));
  h5.commit();
  return dir / "sealed.h5";
}

}  // namespace

TEST(FileSeal, ASealedFileReadsBackAndItsSealIsText) {
  const auto dir = fresh_dir("seal_ok");
  const auto file = sealed_file(dir);
  EXPECT_EQ(refusal(file), "");
  const Hdf5Reader h5(file);
  EXPECT_EQ(h5.matrix("values").rows, 400u);
  EXPECT_GT(std::filesystem::file_size(file), 2u * 65536u);
  EXPECT_EQ(h5.text_attribute("note"), "a sealed file");
  const std::string head = bytes_of(file).substr(0, 40);
  EXPECT_EQ(head.rfind("drom seal 1\nlength " + std::to_string(std::filesystem::file_size(file)) + "\n", 0), 0u) << head;
  std::filesystem::remove_all(dir);
}

TEST(FileSeal, EveryFlippedBitIsFoundAndLocated) {
  // 200 random single-bit flips anywhere in the file: each refused, and the message's byte range
  // holds the flipped byte (or names the seal when the flip is in it).
  const auto dir = fresh_dir("seal_flips");
  const auto file = sealed_file(dir);
  const std::string good = bytes_of(file);
  std::mt19937 rng(27);
  std::uniform_int_distribution<std::size_t> where(0, good.size() - 1);
  std::uniform_int_distribution<int> bit(0, 7);
  int located = 0;
  for (int trial = 0; trial < 200; ++trial) {
    std::string bad = good;
    const std::size_t at = where(rng);
    bad[at] = static_cast<char>(bad[at] ^ (1 << bit(rng)));
    put_bytes(dir / "flipped.h5", bad);
    const std::string why = refusal(dir / "flipped.h5");
    ASSERT_NE(why, "") << "a flip at byte " << at << " was not caught";
    EXPECT_EQ(why.rfind((dir / "flipped.h5").string() + ": ", 0), 0u) << why;
    if (at < kSealBytes) {
      // In the seal: its text no longer parses, or it still parses and then disagrees.
      EXPECT_TRUE(why.find("seal") != std::string::npos || why.find("damaged") != std::string::npos || why.find("truncated") != std::string::npos ||
                  why.find("not a file drom wrote") != std::string::npos || why.find("added after") != std::string::npos)
          << why;
      continue;
    }
    unsigned long long from = 0, to = 0;
    ASSERT_EQ(std::sscanf(why.c_str() + why.find("damaged: bytes ") + 15, "%llu-%llu", &from, &to), 2) << why;
    EXPECT_LE(from, at);
    EXPECT_GE(to, at);
    ++located;
  }
  EXPECT_GT(located, 150);
  std::filesystem::remove_all(dir);
}

TEST(FileSeal, TruncatedExtendedUnsealedAndForeignFilesAreRefusedSayingWhy) {
  const auto dir = fresh_dir("seal_refusals");
  const auto file = sealed_file(dir);
  const std::string good = bytes_of(file);
  put_bytes(dir / "cut.h5", good.substr(0, 3000));
  EXPECT_NE(refusal(dir / "cut.h5").find("truncated: 3000 bytes of the " + std::to_string(good.size()) + " drom wrote (bytes from 3000 on are missing"),
            std::string::npos)
      << refusal(dir / "cut.h5");
  put_bytes(dir / "seal_only.h5", good.substr(0, 100));
  EXPECT_NE(refusal(dir / "seal_only.h5").find("truncated: 100 bytes, not even its 512-byte seal"), std::string::npos) << refusal(dir / "seal_only.h5");
  put_bytes(dir / "longer.h5", good + "tail");
  EXPECT_NE(refusal(dir / "longer.h5").find("bytes from " + std::to_string(good.size()) + " on were added"), std::string::npos) << refusal(dir / "longer.h5");
  std::string unsealed = good;
  std::fill(unsealed.begin(), unsealed.begin() + static_cast<std::ptrdiff_t>(kSealBytes), '\0');
  unsealed.replace(0, 8, "\x89HDF\r\n\x1a\n");
  put_bytes(dir / "unsealed.h5", unsealed);
  EXPECT_NE(refusal(dir / "unsealed.h5").find("an HDF5 file without drom's seal"), std::string::npos) << refusal(dir / "unsealed.h5");
  put_bytes(dir / "text.h5", "depth,sigma11,sigma22\n");
  EXPECT_NE(refusal(dir / "text.h5").find("not a file drom wrote (expected 'drom seal 1' at byte 0)"), std::string::npos) << refusal(dir / "text.h5");
  put_bytes(dir / "empty.h5", "");
  EXPECT_NE(refusal(dir / "empty.h5").find("not a file drom wrote"), std::string::npos);
  EXPECT_NE(refusal(dir / "missing.h5").find("cannot open it"), std::string::npos);
  EXPECT_NE(refusal(dir).find(dir.string()), std::string::npos);  // a folder
  std::filesystem::remove_all(dir);
}

TEST(AtomicFile, ATemporaryOfAWriterThatDiedIsRemovedByTheNextWriter) {
  const auto dir = fresh_dir("atomic_stale");
  // A child writes its temporary and dies before committing (as under SIGKILL); another is still
  // writing (it waits on a pipe, and dies with this test if the test ends first).
  auto writer = [&](int wait_fd) {
    const pid_t child = ::fork();
    if (child == 0) {
      ::prctl(PR_SET_PDEATHSIG, SIGKILL);
      AtomicFile f(dir / "result.csv");
      std::ofstream(f.temporary_path()) << "half";
      char c;
      if (wait_fd >= 0) (void)!::read(wait_fd, &c, 1);
      ::_exit(0);  // no destructor: the temporary stays
    }
    return child;
  };
  const pid_t dead = writer(-1);
  int status = 0;
  ::waitpid(dead, &status, 0);
  const auto stale = dir / (".result.tmp" + std::to_string(dead) + ".csv");
  EXPECT_TRUE(std::filesystem::exists(stale));
  int pipe_fds[2];
  ASSERT_EQ(::pipe(pipe_fds), 0);
  const pid_t alive = writer(pipe_fds[0]);
  const auto live = dir / (".result.tmp" + std::to_string(alive) + ".csv");
  for (int i = 0; i < 500 && !std::filesystem::exists(live); ++i) ::usleep(10000);
  EXPECT_TRUE(std::filesystem::exists(live));
  EXPECT_FALSE(std::filesystem::exists(stale)) << "the live writer, the next one, should have removed it";
  write_file_atomically(dir / "result.csv", "done\n");
  EXPECT_TRUE(std::filesystem::exists(live)) << "a live writer's temporary was removed";
  EXPECT_EQ(bytes_of(dir / "result.csv"), "done\n");
  (void)!::write(pipe_fds[1], "x", 1);
  ::waitpid(alive, &status, 0);
  ::close(pipe_fds[0]);
  ::close(pipe_fds[1]);
  std::filesystem::remove_all(dir);
}
