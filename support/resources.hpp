#pragma once
// Process resource figures reported in summary.json files and benchmarks.
#include <chrono>
#include <cstddef>

namespace drom {

// Peak resident set size of this process so far, in bytes (from getrusage).
std::size_t peak_memory_bytes();

// CPU seconds this process has used so far, every thread together (getrusage: user + system). Beside
// the wall clock it says what a stage cost when other jobs share the cores.
double process_cpu_seconds();

// Wall-clock seconds since `start` (steady clock).
inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace drom
