#pragma once
// Reads an NC program: drom's fast reader when the program keeps to the plain subset
// (gcode_reader.hpp), LinuxCNC's interpreter otherwise (rs274_reader.hpp). Both give the same moves
// where both apply (tests/machine: to the interpreter's printed precision).
#include "machine/nc_program.hpp"
#include "machine/rs274_reader.hpp"

#include <filesystem>
#include <string>

namespace drom::machine {

enum class ReaderChoice { Automatic, Plain, Rs274 };

struct ProgramReadOptions {
  ReaderChoice reader = ReaderChoice::Automatic;
  Rs274Options rs274;
};

NcProgram read_program(const std::filesystem::path& path, const ProgramReadOptions& options = {});
NcProgram parse_program(const std::string& text, const std::string& origin, const ProgramReadOptions& options = {});

}  // namespace drom::machine
