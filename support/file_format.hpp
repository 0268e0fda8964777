#pragma once
// The files one stage writes for another (the snapshot database, the light model) carry their format:
// a name, a format version and the drom that wrote them. A reader refuses any other version with a
// message saying what made the file and what it reads, rather than misreading it.
#include "support/hdf5_reader.hpp"
#include "support/hdf5_writer.hpp"

#include <string>

namespace drom {

struct FileFormat {
  std::string name;  // e.g. "drom snapshot database"
  int version = 1;
};

// The files drom's stages hand each other.
inline const FileFormat kSnapshotDatabase{"drom snapshot database", 3};  // offline/ writes it, reduce/ reads it
inline const FileFormat kLightModel{"drom light model", 3};              // reduce/ writes it, online/ reads it

void write_file_format(Hdf5Writer& file, const FileFormat& format);
// Throws InputError naming the file unless it is `format` at its version.
void check_file_format(const Hdf5Reader& file, const FileFormat& format);

}  // namespace drom
