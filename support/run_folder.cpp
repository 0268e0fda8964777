#include "support/run_folder.hpp"

#include "support/input_error.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <system_error>

namespace drom {

namespace fs = std::filesystem;

namespace {

constexpr const char* kMarker = ".drom_run";  // in every folder a drom run wrote

fs::path normalized(const fs::path& out) {
  fs::path p = fs::absolute(out).lexically_normal();
  if (!p.has_filename()) p = p.parent_path();  // a trailing '/'
  const std::string name = p.filename().string();
  if (name.empty() || name == "." || name == ".." || p == p.root_path())
    throw InputError("--out '" + out.string() + "': expected a folder of its own (not the root, '.' or '..')");
  return p;
}

// `inner` is `outer` or lies inside it (both absolute; symbolic links resolved where they exist).
bool inside(const fs::path& inner, const fs::path& outer) {
  std::error_code ec;
  const fs::path a = fs::weakly_canonical(inner, ec), b = fs::weakly_canonical(outer, ec);
  const auto mismatch = std::mismatch(b.begin(), b.end(), a.begin(), a.end());
  return mismatch.first == b.end();
}

// Hidden siblings of `out`: ".<name><suffix>" (built by appends: GCC 12's -Wrestrict misreads "." + s once inlined).
fs::path hidden_sibling(const fs::path& out, const char* suffix) {
  std::string name = ".";
  name += out.filename().string();
  name += suffix;
  return out.parent_path() / name;
}

fs::path discarded_folder(const fs::path& out) { return hidden_sibling(out, ".discarded"); }
fs::path ready_folder(const fs::path& out) { return hidden_sibling(out, ".ready"); }

// A folder that refuses a file: bad input (exit 2, naming --out), but for a full disk, which is a
// failure of the run (exit 1), to run again once there is room.
[[noreturn]] void cannot_write(const std::string& what, int error) {
  if (error == ENOSPC || error == EDQUOT) throw std::runtime_error(what + ": " + std::strerror(error));
  throw InputError(what + ": " + std::strerror(error));
}

void remove_quietly(const fs::path& p) {
  std::error_code ec;
  fs::remove_all(p, ec);
}

}  // namespace

void check_output_folder(const fs::path& out) {
  const std::string shown = out.string();
  std::error_code ec;
  if (fs::exists(out, ec) && !fs::is_directory(out, ec)) throw InputError("--out " + shown + ": a file is there, not a folder");
  fs::create_directories(out, ec);
  if (ec) throw InputError("--out " + shown + ": cannot create the folder: " + ec.message());
  const fs::path probe = out / ".drom_probe";  // one name: a killed check's probe is the next one's
  {
    std::ofstream f(probe);
    f << "drom checks the folder takes files\n";
    f.flush();
    if (!f) {
      const int error = errno;
      fs::remove(probe, ec);
      cannot_write("--out " + shown + ": cannot write in it", error);
    }
  }
  fs::remove(probe, ec);
}

fs::path partial_folder(const fs::path& out) {
  const fs::path p = normalized(out);
  return p.parent_path() / (p.filename().string() + ".partial");
}

RunFolder::RunFolder(fs::path out, const RunFolderOptions& options) : out_(normalized(out)), staging_(partial_folder(out_)) {
  const std::string shown = out.string();
  std::error_code ec;
  if (fs::exists(out_, ec) && !fs::is_directory(out_, ec)) throw InputError("--out " + shown + ": a file is there, not a folder");
  // What a run may replace: a folder a drom run wrote, or an empty one; never the user's own.
  if (inside(fs::current_path(), out_)) throw InputError("--out " + shown + ": the current folder lies in it, and a run replaces its folder whole: give a folder of its own");
  for (const auto& input : options.inputs)
    if (!input.empty() && inside(fs::absolute(input), out_))
      throw InputError("--out " + shown + ": the input " + input.string() + " lies in it, and a run replaces its folder whole: give a folder of its own");
  if (fs::is_directory(out_, ec) && !fs::exists(out_ / kMarker, ec) && !fs::is_empty(out_, ec))
    throw InputError("--out " + shown + ": a folder of files drom did not write (no " + kMarker +
                     "), and a run replaces its folder whole: give a new or empty folder, or one an earlier drom run wrote");
  fs::create_directories(out_.parent_path(), ec);
  if (ec) throw InputError("--out " + shown + ": cannot create the folder " + out_.parent_path().string() + ": " + ec.message());

  lock_path_ = hidden_sibling(out_, ".lock");
  lock_fd_ = ::open(lock_path_.c_str(), O_CREAT | O_RDWR | O_CLOEXEC, 0644);
  if (lock_fd_ < 0) throw InputError("--out " + shown + ": cannot write in " + out_.parent_path().string() + ": " + std::strerror(errno));
  if (::flock(lock_fd_, LOCK_EX | LOCK_NB) != 0) {
    ::close(lock_fd_);
    lock_fd_ = -1;
    throw InputError("--out " + shown + ": another drom is writing this folder now (it holds " + lock_path_.string() + ")");
  }
  ready_ = ready_folder(out_);
  remove_quietly(discarded_folder(out_));  // what a commit killed halfway left
  remove_quietly(ready_);

  if (options.resume && fs::is_directory(staging_, ec)) {
    // Only what the run reuses is taken over: a file the resumed run would not write again (a
    // program it now refuses, a packet it no longer makes) must not survive beside its files.
    resumed_partial_ = true;
    std::vector<fs::path> stale;
    for (const auto& entry : fs::directory_iterator(staging_, ec)) {
      const std::string name = entry.path().filename().string();
      const bool reused = std::any_of(options.reused.begin(), options.reused.end(), [&](const std::string& r) { return *fs::path(r).begin() == name; });
      if (!reused && name != kMarker) stale.push_back(entry.path());
    }
    for (const auto& p : stale) {
      fs::remove_all(p, ec);
      if (ec) throw InputError("--out " + shown + ": cannot clear " + p.string() + " from a killed run's folder: " + ec.message());
    }
  } else {
    fs::remove_all(staging_, ec);
    if (ec) throw InputError("--out " + shown + ": cannot clear " + staging_.string() + ", a failed run's folder: " + ec.message());
    fs::create_directory(staging_, ec);
    if (ec) throw InputError("--out " + shown + ": cannot create " + staging_.string() + ": " + ec.message());
    if (options.resume && fs::is_directory(out_, ec))
      for (const auto& entry : options.reused) {
        const fs::path from = out_ / entry, to = staging_ / entry;
        if (!fs::exists(from, ec)) continue;
        fs::create_directories(to.parent_path(), ec);
        fs::copy(from, to, fs::copy_options::recursive | fs::copy_options::create_hard_links, ec);
        if (ec) throw InputError("--out " + shown + ": cannot reuse " + from.string() + ": " + ec.message());
      }
  }
  // A folder that exists but refuses files (read-only, full) is found now, not after the work; the
  // marker says, once the folder is in place, that a drom run wrote it.
  {
    std::ofstream f(staging_ / kMarker);
    f << "a folder written by drom: a run replaces it whole (support/run_folder.hpp)\n";
    f.flush();
    if (!f) cannot_write("--out " + shown + ": cannot write in " + staging_.string(), errno);
  }
}

RunFolder::~RunFolder() {
  if (lock_fd_ >= 0) ::close(lock_fd_);
}

void RunFolder::commit() {
  if (committed_) return;
  auto fail = [&](const std::string& what) { throw std::runtime_error("cannot put " + staging_.string() + " in place of " + out_.string() + ": " + what); };
  std::error_code ec;
  // The complete run leaves `.partial` first, so that `--resume` never takes a complete run (nor,
  // after the swap, the one it replaced) for a killed one's work.
  fs::rename(staging_, ready_, ec);
  if (ec) fail(ec.message());
  if (fs::exists(out_, ec)) {
    // One atomic swap when the file system has it; else two renames with the old run set aside first.
    if (::renameat2(AT_FDCWD, ready_.c_str(), AT_FDCWD, out_.c_str(), RENAME_EXCHANGE) == 0) {
      fs::rename(ready_, discarded_folder(out_), ec);
      if (ec) fail(ec.message());
    } else if (errno == EINVAL || errno == ENOSYS || errno == ENOTSUP) {
      fs::rename(out_, discarded_folder(out_), ec);
      if (ec) fail(ec.message());
      fs::rename(ready_, out_, ec);
      if (ec) fail(ec.message());
    } else {
      fail(std::strerror(errno));
    }
    remove_quietly(discarded_folder(out_));
  } else {
    fs::rename(ready_, out_, ec);
    if (ec) fail(ec.message());
  }
  committed_ = true;
}

}  // namespace drom
