// Harness: a face of a STEP file (geometry/step_face.hpp, OpenCASCADE's reader underneath), as a
// finishing case's `step = "file.step"` reads it: the face count, then face 1 as drom's NURBS patch.
// Seeds: a Bézier patch, a trimmed plane and a vertex-only file, written with OpenCASCADE.
#include "fuzz/fuzz_input.hpp"
#include "geometry/step_face.hpp"

#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>

namespace {
// OpenCASCADE runs in a worker forked from this process (geometry/step_face.cpp). clang 14's ASan
// allocator does not lock itself around fork(), so a worker forked while another thread is inside it
// waits forever on that thread's lock. Here that thread is libFuzzer's RSS watcher, started just
// before the first input, whose start allocates (a new thread's ASan state): forked then, the
// first worker hung in 7 runs of 10. Every other thread here only sleeps once started (the watcher,
// log4cplus's pool loaded with OpenVDB), so the first read waits until they all are. (A Release
// build uses glibc's malloc, which fork() leaves consistent.)
void wait_until_other_threads_sleep() {
  const auto all_others_asleep = [] {
    const std::string self = std::to_string(::gettid());
    for (const auto& task : std::filesystem::directory_iterator("/proc/self/task")) {
      if (task.path().filename() == self) continue;
      std::ifstream stat(task.path() / "stat");
      std::string line;
      std::getline(stat, line);
      const auto close = line.rfind(')');
      if (close == std::string::npos || close + 2 >= line.size() || line[close + 2] != 'S') return false;
    }
    return true;
  };
  for (int settled = 0, round = 0; settled < 3 && round < 500; ++round) {
    settled = all_others_asleep() ? settled + 1 : 0;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const bool settled = (wait_until_other_threads_sleep(), true);
  (void)settled;
  const auto file = drom::fuzz::as_file(data, size, "fuzz_face.step");
  drom::fuzz::expect_clean(
      [&] {
        const int faces = drom::geometry::count_step_faces(file);
        drom::fuzz::require(faces >= 1, "a face count below 1 returned instead of an error");
        const auto face = drom::geometry::read_step_face(file, 1);
        const auto p = face.surface.point(0.5, 0.5);
        drom::fuzz::require(p.allFinite(), "a face whose surface evaluates to a non-finite point");
      },
      file.string());
  return 0;
}
