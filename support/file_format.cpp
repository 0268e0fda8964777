#include "support/file_format.hpp"

#include "support/input_error.hpp"
#include "support/version.hpp"

#include <cmath>

namespace drom {

void write_file_format(Hdf5Writer& file, const FileFormat& format) {
  file.attribute("format", format.name);
  file.attribute("format_version", static_cast<double>(format.version));
  file.attribute("written_by", std::string("drom ") + kVersion);
}

void check_file_format(const Hdf5Reader& file, const FileFormat& format) {
  const std::string where = file.path().string() + ": ";
  const std::string reads = "this drom (" + std::string(kVersion) + ") reads " + format.name + " format version " + std::to_string(format.version);
  if (!file.has_attribute("format_version"))
    throw InputError(where + "made by a drom from before format versions (0.1.x); " + reads + ". Write it again with this drom");
  const std::string name = file.has_attribute("format") ? file.text_attribute("format") : "";
  if (name != format.name) throw InputError(where + "is a '" + name + "', expected a " + format.name);
  const double version = file.number_attribute("format_version");
  if (version != format.version) {
    const std::string by = file.has_attribute("written_by") ? file.text_attribute("written_by") : "an unknown drom";
    throw InputError(where + "format version " + std::to_string(static_cast<long long>(std::llround(version))) + ", made by " + by + "; " + reads +
                     (version > format.version ? ": update drom to read it" : ": write it again with this drom"));
  }
}

}  // namespace drom
