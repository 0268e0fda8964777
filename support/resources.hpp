#pragma once
// Process resource figures reported in summary.json files and benchmarks.
#include <cstddef>

namespace drom {

// Peak resident set size of this process so far, in bytes (from getrusage).
std::size_t peak_memory_bytes();

}  // namespace drom
