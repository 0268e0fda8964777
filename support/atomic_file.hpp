#pragma once
// Atomic file output: write next to the destination, then rename over it, so a reader (or a
// resumed run) never sees a half-written file. A temporary left by a writer that died (SIGKILL, a
// stopped machine) is removed by the next writer of the same destination.
#include <filesystem>
#include <string>
#include <string_view>

namespace drom {

// Writes `content` to `path` atomically; creates parent folders. Throws std::runtime_error on failure,
// with the system's reason (a full disk: "No space left on device"); nothing is left at `path` then.
void write_file_atomically(const std::filesystem::path& path, std::string_view content);

// For writers that need a file name of their own (VTK, HDF5): write to temporary_path(), then commit().
// If commit() is never called the temporary file is removed.
class AtomicFile {
 public:
  explicit AtomicFile(std::filesystem::path destination);
  ~AtomicFile();
  AtomicFile(const AtomicFile&) = delete;
  AtomicFile& operator=(const AtomicFile&) = delete;

  const std::filesystem::path& temporary_path() const { return temporary_; }
  void commit();

 private:
  std::filesystem::path destination_;
  std::filesystem::path temporary_;
  bool committed_ = false;
};

}  // namespace drom
