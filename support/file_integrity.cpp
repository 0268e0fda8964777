#include "support/file_integrity.hpp"

#include "support/input_error.hpp"

#include <zlib.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

namespace drom {

namespace {

constexpr int kSegments = 32;
constexpr char kMagic[] = "drom seal 1\n";

struct Seal {
  std::uint64_t length = 0, segment = 1;
  std::array<std::uint32_t, kSegments> crc{};
};

std::uint64_t segment_length(std::uint64_t length) {
  const std::uint64_t body = length > kSealBytes ? length - kSealBytes : 0;
  return std::max<std::uint64_t>(1, (body + kSegments - 1) / kSegments);
}

// CRC-32 of each segment of the bytes after the seal, reading `in` from kSealBytes on; `read` is the
// number of bytes found there.
std::array<std::uint32_t, kSegments> segment_crcs(std::istream& in, std::uint64_t segment, std::uint64_t& read) {
  std::array<std::uint32_t, kSegments> crc{};
  for (auto& c : crc) c = static_cast<std::uint32_t>(crc32(0L, Z_NULL, 0));
  in.seekg(static_cast<std::streamoff>(kSealBytes));
  // 64 KiB: zlib's crc32 runs at full speed on it, and a buffer this size stays in the allocator's
  // small-block pools (a 1 MiB one was mapped, zeroed and unmapped at every seal and check).
  std::vector<char> buffer(std::size_t{1} << 16);
  read = 0;
  while (in) {
    in.read(buffer.data(), static_cast<std::streamsize>(buffer.size()));
    const auto got = static_cast<std::uint64_t>(in.gcount());
    for (std::uint64_t done = 0; done < got;) {
      const std::uint64_t at = read + done, index = std::min<std::uint64_t>(at / segment, kSegments - 1);
      const std::uint64_t end = index == kSegments - 1 ? got : std::min(got, (index + 1) * segment - read);
      auto& c = crc[static_cast<std::size_t>(index)];
      c = static_cast<std::uint32_t>(crc32(c, reinterpret_cast<const Bytef*>(buffer.data() + done), static_cast<uInt>(end - done)));
      done = end;
    }
    read += got;
  }
  return crc;
}

std::string seal_text(const Seal& s) {
  std::string text = kMagic;
  text += "length " + std::to_string(s.length) + "\nsegment " + std::to_string(s.segment) + "\ncrc32";
  for (const auto c : s.crc) {
    char hex[10];
    std::snprintf(hex, sizeof hex, " %08" PRIx32, c);
    text += hex;
  }
  return text + "\n";
}

}  // namespace

void seal_file(const std::filesystem::path& path) {
  std::fstream file(path, std::ios::in | std::ios::out | std::ios::binary);
  if (!file) throw std::runtime_error("cannot reopen " + path.string() + " to seal it: " + std::strerror(errno));
  Seal s;
  s.length = std::filesystem::file_size(path);
  if (s.length < kSealBytes) throw std::runtime_error(path.string() + ": no room reserved for its seal");
  s.segment = segment_length(s.length);
  std::uint64_t read = 0;
  s.crc = segment_crcs(file, s.segment, read);
  if (read + kSealBytes != s.length) throw std::runtime_error("cannot read back " + path.string() + " to seal it");
  file.clear();
  file.seekp(0);
  const std::string text = seal_text(s);
  file.write(text.data(), static_cast<std::streamsize>(text.size()));
  file.flush();
  if (!file) throw std::runtime_error("cannot write the seal of " + path.string() + ": " + std::strerror(errno));
}

void check_seal(const std::filesystem::path& path) {
  const std::string where = path.string() + ": ";
  std::ifstream in(path, std::ios::binary);
  if (!in) throw InputError(where + "cannot open it");
  std::error_code ec;
  const std::uint64_t size = std::filesystem::file_size(path, ec);
  if (ec) throw InputError(where + "not a regular file");
  std::array<char, kSealBytes> head{};
  in.read(head.data(), static_cast<std::streamsize>(head.size()));
  const auto got = static_cast<std::size_t>(in.gcount());
  if (got < sizeof kMagic - 1 || std::memcmp(head.data(), kMagic, sizeof kMagic - 1) != 0) {
    if (got >= 4 && std::memcmp(head.data(), "\x89HDF", 4) == 0)
      throw InputError(where + "an HDF5 file without drom's seal in its first " + std::to_string(kSealBytes) +
                       " bytes: written by a drom before format version 3, or by another program; write it again with this drom");
    throw InputError(where + "not a file drom wrote (expected '" + std::string(kMagic, sizeof kMagic - 2) + "' at byte 0)");
  }
  if (size < kSealBytes)
    throw InputError(where + "truncated: " + std::to_string(size) + " bytes, not even its " + std::to_string(kSealBytes) + "-byte seal");
  // The seal's text: the magic, the length, the segment length and 32 CRCs, then zeros.
  Seal s;
  const std::string text(head.data(), std::find(head.begin(), head.end(), '\0'));
  std::istringstream fields(text.substr(sizeof kMagic - 1));
  std::string word1, word2, word3;
  fields >> word1 >> s.length >> word2 >> s.segment >> word3;
  for (auto& c : s.crc) fields >> std::hex >> c;
  if (!fields || word1 != "length" || word2 != "segment" || word3 != "crc32" || s.segment != segment_length(s.length) || seal_text(s) != text)
    throw InputError(where + "its seal (bytes 0-" + std::to_string(kSealBytes - 1) + ") is damaged");
  if (size < s.length)
    throw InputError(where + "truncated: " + std::to_string(size) + " bytes of the " + std::to_string(s.length) + " drom wrote (bytes from " + std::to_string(size) +
                     " on are missing: an interrupted copy or a full disk?)");
  if (size > s.length)
    throw InputError(where + std::to_string(size) + " bytes, but drom wrote " + std::to_string(s.length) + ": bytes from " + std::to_string(s.length) +
                     " on were added after it was written");
  in.clear();
  std::uint64_t read = 0;
  const auto crc = segment_crcs(in, s.segment, read);
  if (read + kSealBytes != s.length) throw InputError(where + "cannot read it whole");
  int damaged = 0, first = -1;
  for (int i = 0; i < kSegments; ++i)
    if (crc[static_cast<std::size_t>(i)] != s.crc[static_cast<std::size_t>(i)]) {
      ++damaged;
      if (first < 0) first = i;
    }
  if (damaged > 0) {
    const std::uint64_t from = kSealBytes + static_cast<std::uint64_t>(first) * s.segment;
    const std::uint64_t to = first == kSegments - 1 ? s.length : std::min(s.length, from + s.segment);
    throw InputError(where + "damaged: bytes " + std::to_string(from) + "-" + std::to_string(to - 1) + " differ from what drom wrote (CRC-32)" +
                     (damaged > 1 ? ", and " + std::to_string(damaged - 1) + " more of its " + std::to_string(kSegments) + " segments" : std::string()) +
                     "; the file was changed or corrupted after it was written");
  }
}

}  // namespace drom
