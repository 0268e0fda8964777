#include "support/atomic_file.hpp"

#include <fstream>
#include <stdexcept>
#include <system_error>
#include <unistd.h>

namespace drom {

namespace {
std::filesystem::path sibling_temporary(const std::filesystem::path& destination) {
  // Same folder (rename is atomic only within one file system); the pid keeps parallel writers apart.
  // The extension is kept because some writers (VTK) pick the format from it.
  std::string name(".");
  name.append(destination.stem().string()).append(".tmp").append(std::to_string(::getpid())).append(destination.extension().string());
  return destination.parent_path() / name;
}

void ensure_parent(const std::filesystem::path& path) {
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
}
}  // namespace

void write_file_atomically(const std::filesystem::path& path, std::string_view content) {
  AtomicFile file(path);
  {
    std::ofstream out(file.temporary_path(), std::ios::binary | std::ios::trunc);
    if (!out) throw std::runtime_error("cannot write " + file.temporary_path().string());
    out.write(content.data(), static_cast<std::streamsize>(content.size()));
    out.flush();
    if (!out) throw std::runtime_error("write failed for " + file.temporary_path().string());
  }
  file.commit();
}

AtomicFile::AtomicFile(std::filesystem::path destination)
    : destination_(std::move(destination)), temporary_(sibling_temporary(destination_)) {
  ensure_parent(destination_);
}

AtomicFile::~AtomicFile() {
  if (!committed_) {
    std::error_code ignored;
    std::filesystem::remove(temporary_, ignored);
  }
}

void AtomicFile::commit() {
  std::error_code ec;
  std::filesystem::rename(temporary_, destination_, ec);
  if (ec) throw std::runtime_error("cannot move " + temporary_.string() + " to " + destination_.string() + ": " + ec.message());
  committed_ = true;
}

}  // namespace drom
