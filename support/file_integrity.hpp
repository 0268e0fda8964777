#pragma once
// A seal on the files drom writes for itself (the snapshot database, the light model, every HDF5 file):
// the first kSealBytes bytes (an HDF5 user block, which HDF5 and h5py skip) hold, in text, the file's
// length and a CRC-32 of each of 32 equal segments of the rest. A reader checks the seal before any
// parser sees the bytes, so a truncated, bit-flipped or otherwise changed file is refused with the
// byte range that differs, instead of reaching a parser (libhdf5) that may crash on it.
// The seal guards against damage, not against forgery: a file made to pass it is not vetted further.
#include <cstddef>
#include <filesystem>

namespace drom {

inline constexpr std::size_t kSealBytes = 512;

// Writes the seal into the first kSealBytes of `path` (reserved, and left zero, by its writer) for
// the bytes after them. Throws std::runtime_error when the file cannot be read back or written.
void seal_file(const std::filesystem::path& path);
// Throws InputError naming the file and what is wrong with it (missing seal, length, damaged byte range).
void check_seal(const std::filesystem::path& path);

}  // namespace drom
