#pragma once
// A folder for one test process's files under the system's temporary folder, named after `prefix` and
// the process id, and removed with everything in it when the process ends (set DROM_KEEP_TEST_FILES
// to keep it and look). ctest runs every test in its own process: a folder kept per process left
// gigabytes of scans, copies and programs behind after a few runs.
#include <cstdlib>
#include <filesystem>
#include <string>
#include <unistd.h>

namespace drom::tests {

inline std::filesystem::path scratch_folder(const std::string& prefix) {
  struct Folder {
    std::filesystem::path path;
    pid_t owner = 0;
    ~Folder() {
      // A forked child that returns through exit() must not take its parent's files.
      if (path.empty() || owner != ::getpid() || std::getenv("DROM_KEEP_TEST_FILES")) return;
      std::error_code ignored;
      std::filesystem::remove_all(path, ignored);
    }
  };
  static Folder folder;
  const std::filesystem::path p = std::filesystem::temp_directory_path() / (prefix + std::to_string(::getpid()));
  if (folder.path.empty()) folder.path = p, folder.owner = ::getpid();
  std::filesystem::create_directories(p);
  return p;
}

}  // namespace drom::tests
