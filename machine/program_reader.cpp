#include "machine/program_reader.hpp"

#include "machine/gcode_reader.hpp"
#include "support/input_error.hpp"

#include <cstdlib>
#include <fstream>
#include <sstream>
#include <unistd.h>

namespace drom::machine {

namespace fs = std::filesystem;

NcProgram read_program(const fs::path& path, const ProgramReadOptions& options) {
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open program");
  if (options.reader == ReaderChoice::Rs274) return read_with_rs274(path, options.rs274);
  std::ostringstream text;
  text << in.rdbuf();
  try {
    return parse_plain_gcode(text.str(), path.string());
  } catch (const OutsidePlainSubset&) {
    if (options.reader == ReaderChoice::Plain) throw;
    return read_with_rs274(path, options.rs274);
  }
}

NcProgram parse_program(const std::string& text, const std::string& origin, const ProgramReadOptions& options) {
  if (options.reader != ReaderChoice::Rs274) {
    try {
      return parse_plain_gcode(text, origin);
    } catch (const OutsidePlainSubset&) {
      if (options.reader == ReaderChoice::Plain) throw;
    }
  }
  // The interpreter reads files: give it the text in a scratch file named after the origin.
  std::string pattern = (fs::temp_directory_path() / "drom-program-XXXXXX").string();
  const int fd = ::mkstemp(pattern.data());
  if (fd < 0) throw std::runtime_error("cannot create a scratch file for rs274");
  ::close(fd);
  struct Remove {
    fs::path p;
    ~Remove() {
      std::error_code ec;
      fs::remove(p, ec);
    }
  } remove{pattern};
  std::ofstream(pattern) << text;
  try {
    NcProgram program = read_with_rs274(pattern, options.rs274);
    program.origin = origin;
    return program;
  } catch (const InputError& e) {
    std::string message = e.what();
    for (auto at = message.find(pattern); at != std::string::npos; at = message.find(pattern)) message.replace(at, pattern.size(), origin);
    throw InputError(message);
  }
}

}  // namespace drom::machine
