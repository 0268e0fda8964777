// keep_freed_memory: a large block freed and asked for again is served from the kept heap, not
// mapped afresh and faulted in page by page (what a station's solve does with its factors).
#include "support/heap_policy.hpp"

#include <gtest/gtest.h>
#include <sys/resource.h>

#include <cstdlib>
#include <cstring>

namespace {

// AddressSanitizer replaces malloc with its own allocator (freed blocks wait in a quarantine and
// glibc's mallopt settings do not apply to it), so the policy cannot be observed in that build.
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kAddressSanitizer = true;
#else
constexpr bool kAddressSanitizer = false;
#endif
#else
constexpr bool kAddressSanitizer = false;
#endif

long minor_faults() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return usage.ru_minflt;
}

// Page faults while a block of `bytes` is allocated, written and freed.
long faults_of_a_block(std::size_t bytes) {
  const long before = minor_faults();
  auto* block = static_cast<char*>(std::malloc(bytes));
  if (!block) return -1;
  std::memset(block, 1, bytes);
  const volatile char sink = block[bytes / 2];
  (void)sink;
  std::free(block);
  return minor_faults() - before;
}

}  // namespace

TEST(HeapPolicy, ALargeBlockFreedAndAskedForAgainIsNotFaultedInAgain) {
  if (kAddressSanitizer) GTEST_SKIP() << "glibc's heap policy does not apply under AddressSanitizer's allocator";
  constexpr std::size_t bytes = 64u << 20;  // 16 384 pages of 4 kB
  drom::keep_freed_memory();
  const long first = faults_of_a_block(bytes);
  const long second = faults_of_a_block(bytes);
  ASSERT_GT(first, 0) << "the first use faults its pages in";
  // Without the policy the second is a fresh mmap and faults as much as the first (16 384 pages, or
  // 32 with transparent huge pages).
  EXPECT_LT(10 * second, first) << "first " << first << " faults, second " << second;
}
