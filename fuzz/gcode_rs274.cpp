// Harness: a G-code program in the whole RS274/NGC language, read the way drom reads a program outside
// its plain subset: LinuxCNC's interpreter rs274 run as a process, its canonical calls read back
// (machine/rs274_reader.hpp). rs274 itself is not instrumented: this covers drom's side (the program
// handed over, the output parsed, a refusal turned into a message naming the line). One process per
// input: a smoke test, not a 10^6-execution run. Seeds: the gcode harness's, and a program with
// parameters, expressions and an O-word loop.
#include "fuzz/fuzz_input.hpp"
#include "machine/program_reader.hpp"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string origin = "fuzz.ngc";
  drom::machine::ProgramReadOptions options;
  options.reader = drom::machine::ReaderChoice::Rs274;
  drom::fuzz::expect_clean(
      [&] {
        const auto program = drom::machine::parse_program(drom::fuzz::as_text(data, size), origin, options);
        for (const auto& m : program.moves)
          drom::fuzz::require(m.start.allFinite() && m.end.allFinite() && m.centre.allFinite() && std::isfinite(m.programmed_duration()),
                              "a move with a non-finite position or duration");
      },
      origin);
  return 0;
}
