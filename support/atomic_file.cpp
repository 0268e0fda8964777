#include "support/atomic_file.hpp"

#include <cerrno>
#include <csignal>
#include <cstring>
#include <stdexcept>
#include <system_error>

#include <fcntl.h>
#include <unistd.h>

namespace drom {

namespace {
std::string temporary_prefix(const std::filesystem::path& destination) {
  std::string prefix(".");  // appended, not "." + ...: GCC 12 warns falsely (-Wrestrict) on that operator+
  return prefix.append(destination.stem().string()).append(".tmp");
}

std::filesystem::path sibling_temporary(const std::filesystem::path& destination) {
  // Same folder (rename is atomic only within one file system); the pid keeps parallel writers apart.
  // The extension is kept because some writers (VTK) pick the format from it.
  return destination.parent_path() / (temporary_prefix(destination) + std::to_string(::getpid()) + destination.extension().string());
}

void ensure_parent(const std::filesystem::path& path) {
  if (path.has_parent_path()) std::filesystem::create_directories(path.parent_path());
}

// The temporaries of this destination left by writers that died (killed, or the machine stopped):
// their pid no longer runs. A live writer's are left alone.
void remove_stale_temporaries(const std::filesystem::path& destination) {
  const std::string prefix = temporary_prefix(destination), extension = destination.extension().string();
  std::error_code ec;
  const auto folder = destination.has_parent_path() ? destination.parent_path() : std::filesystem::path(".");
  for (std::filesystem::directory_iterator it(folder, ec), end; !ec && it != end; it.increment(ec)) {
    const std::string name = it->path().filename().string();
    if (name.size() <= prefix.size() + extension.size() || name.compare(0, prefix.size(), prefix) != 0 ||
        name.compare(name.size() - extension.size(), extension.size(), extension) != 0)
      continue;
    const std::string digits = name.substr(prefix.size(), name.size() - prefix.size() - extension.size());
    if (digits.empty() || digits.size() > 9 || digits.find_first_not_of("0123456789") != std::string::npos) continue;
    const auto pid = static_cast<pid_t>(std::stol(digits));
    if (pid == ::getpid() || ::kill(pid, 0) == 0 || errno != ESRCH) continue;
    std::error_code ignored;
    std::filesystem::remove(it->path(), ignored);
  }
}

std::string reason() { return errno != 0 ? std::string(": ") + std::strerror(errno) : std::string(); }
}  // namespace

void write_file_atomically(const std::filesystem::path& path, std::string_view content) {
  AtomicFile file(path);
  // POSIX calls rather than a stream: a short write's errno (ENOSPC, EDQUOT, EIO) goes in the message.
  errno = 0;
  const int fd = ::open(file.temporary_path().c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd < 0) throw std::runtime_error("cannot write " + file.temporary_path().string() + reason());
  for (std::size_t done = 0; done < content.size();) {
    const ssize_t n = ::write(fd, content.data() + done, content.size() - done);
    if (n < 0 && errno == EINTR) continue;
    if (n <= 0) {
      const int error = errno;
      ::close(fd);
      errno = error;
      throw std::runtime_error("cannot write " + path.string() + " (" + std::to_string(done) + " of " + std::to_string(content.size()) + " bytes written)" + reason());
    }
    done += static_cast<std::size_t>(n);
  }
  if (::close(fd) != 0) throw std::runtime_error("cannot write " + path.string() + reason());
  file.commit();
}

AtomicFile::AtomicFile(std::filesystem::path destination)
    : destination_(std::move(destination)), temporary_(sibling_temporary(destination_)) {
  ensure_parent(destination_);
  remove_stale_temporaries(destination_);
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
