#pragma once
// What every harness shares (fuzz/README.md). The rule a reader is held to: on any bytes it returns a
// result that passes the harness's checks, or throws drom::InputError whose message starts with the
// input's name and says what is wrong. Anything else is a finding: another exception, a crash, UB
// (UBSan), a leak (LeakSanitizer), a hang (-timeout) or an allocation past -malloc_limit_mb.
#include "support/input_error.hpp"

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>
#include <initializer_list>
#include <string>
#include <string_view>
#include <typeinfo>
#include <utility>

#include <fcntl.h>
#include <unistd.h>

namespace drom::fuzz {

// The input as text (NUL bytes and all).
inline std::string as_text(const std::uint8_t* data, std::size_t size) { return {reinterpret_cast<const char*>(data), size}; }

// A folder of this process's own for input files: on /dev/shm (memory) when there is one.
inline const std::filesystem::path& scratch_dir() {
  static const std::filesystem::path dir = [] {
    const std::filesystem::path base = std::filesystem::is_directory("/dev/shm") ? std::filesystem::path("/dev/shm") : std::filesystem::temp_directory_path();
    auto d = base / ("drom_fuzz_" + std::to_string(::getpid()));
    std::filesystem::create_directories(d);
    std::atexit([] { std::error_code ignored; std::filesystem::remove_all(scratch_dir(), ignored); });
    return d;
  }();
  return dir;
}

// The bytes written to scratch_dir()/name (the extension matters to some readers); the same file each
// call, so a reader that reads by path sees exactly the input.
inline std::filesystem::path as_file(const std::uint8_t* data, std::size_t size, const std::string& name) {
  const auto path = scratch_dir() / name;
  std::error_code ignored;
  std::filesystem::create_directories(scratch_dir(), ignored);  // again, should a cleaner have removed it
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0600);
  if (fd < 0) std::abort();
  for (std::size_t done = 0; done < size;) {
    const ssize_t n = ::write(fd, data + done, size - done);
    if (n <= 0) std::abort();
    done += static_cast<std::size_t>(n);
  }
  ::close(fd);
  return path;
}

[[noreturn]] inline void finding(const std::string& what) {
  std::fprintf(stderr, "\n*** drom fuzz finding: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();  // libFuzzer saves the input as crash-<sha1>
}

// Runs `read` under the rule above; `origins` are the names the reader was given for its input (an
// error must start with one of them).
template <class Read>
void expect_clean(Read&& read, std::initializer_list<std::string_view> origins) {
  try {
    read();
  } catch (const InputError& e) {
    const std::string_view what = e.what();
    for (const auto origin : origins)
      if (what.substr(0, origin.size()) == origin && what.size() >= origin.size() + 4) return;
    finding("an InputError that does not start with the input's name (" + std::string(*origins.begin()) + "): " + std::string(what));
  } catch (const std::exception& e) {
    finding(std::string("an exception other than InputError: ") + typeid(e).name() + ": " + e.what());
  } catch (...) {
    finding("a non-standard exception");
  }
}
template <class Read>
void expect_clean(Read&& read, const std::string& origin) {
  expect_clean(std::forward<Read>(read), {std::string_view(origin)});
}

// A result check inside `read`: a reader that returns must not return nonsense (NaN, a size that
// contradicts its input): the "silent wrong answer" the house rules forbid.
inline void require(bool ok, const std::string& what) {
  if (!ok) finding("accepted input gave a wrong result: " + what);
}

}  // namespace drom::fuzz
