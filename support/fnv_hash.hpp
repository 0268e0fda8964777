#pragma once
// FNV-1a, 64 bits: the fingerprints drom writes into its files (a case's hash, a database's content
// hash, a checkpoint's job key). Not cryptographic: it tells files apart, it does not guard them.
#include <cinttypes>
#include <cstdint>
#include <cstdio>
#include <string>
#include <string_view>

namespace drom {

inline constexpr std::uint64_t kFnvOffset = 1469598103934665603ull;

inline std::uint64_t fnv1a(const void* data, std::size_t bytes, std::uint64_t hash = kFnvOffset) {
  const auto* p = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < bytes; ++i) hash = (hash ^ p[i]) * 1099511628211ull;
  return hash;
}
inline std::uint64_t fnv1a(std::string_view text, std::uint64_t hash = kFnvOffset) { return fnv1a(text.data(), text.size(), hash); }

// 16 lowercase hex digits.
inline std::string hex(std::uint64_t v) {
  char buf[20];
  std::snprintf(buf, sizeof buf, "%016" PRIx64, v);
  return buf;
}

}  // namespace drom
