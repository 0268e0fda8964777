#pragma once
// A run's output folder, owned by the run from start to end. The run writes into a staging folder
// beside it, `<out>.partial`, and commit() swaps that in for `<out>` in one rename (Linux's
// renameat2 RENAME_EXCHANGE), then deletes what was there. So:
// - a run killed or failed midway leaves `<out>` as the last complete run left it, and its own work
//   in `<out>.partial`, a folder whose name says what it is;
// - nothing of an earlier run survives beside a new one: `<out>` is always one run's files;
// - only `--resume` reuses earlier work, and only the entries the command names: those of a killed
//   run's `.partial` folder (the rest of it is cleared), or else those of `<out>` (hard links, so
//   nothing is copied), nothing more.
// The constructor checks, before any long work, that the folder can be made and written, and that no
// other drom is writing it (an advisory lock beside it). A folder is only ever replaced when a drom run
// wrote it (its `.drom_run` marker) or it is empty: `--out .`, `--out ~` or a folder of the user's own
// files is refused, as is a folder holding the current directory or one of the run's inputs.
#include <filesystem>
#include <string>
#include <vector>

namespace drom {

struct RunFolderOptions {
  bool resume = false;
  // With resume: the entries the run reuses (relative paths, e.g. "optimization"), from a killed
  // run's `.partial` folder or else from the last complete run; the others are not carried over.
  std::vector<std::string> reused;
  // The run's input files: none may lie inside the folder it replaces.
  std::vector<std::filesystem::path> inputs;
};

class RunFolder {
 public:
  explicit RunFolder(std::filesystem::path out, const RunFolderOptions& options = {});
  ~RunFolder();
  RunFolder(const RunFolder&) = delete;
  RunFolder& operator=(const RunFolder&) = delete;

  // Where the run writes (the staging folder), and where its files are once committed.
  const std::filesystem::path& staging() const { return staging_; }
  const std::filesystem::path& out() const { return out_; }
  // True when the run took over a killed run's `.partial` folder (resume only).
  bool resumed_partial() const { return resumed_partial_; }
  // Swaps the staging folder in for `out`. Throws std::runtime_error with the system's reason.
  void commit();

 private:
  std::filesystem::path out_, staging_, ready_, lock_path_;
  int lock_fd_ = -1;
  bool resumed_partial_ = false, committed_ = false;
};

// For the commands that write straight into their folder (support/summary.hpp, clear_earlier_run):
// makes `out` and checks, before any long work, that it is a folder and takes files. InputError
// naming --out otherwise (a file in the way, a read-only file system); a full disk is a
// std::runtime_error (the run fails, exit 1, and can run again once there is room).
void check_output_folder(const std::filesystem::path& out);

// The staging folder of `out`: `<out>.partial`.
std::filesystem::path partial_folder(const std::filesystem::path& out);

}  // namespace drom
