// Harness: drom's side of LinuxCNC's interpreter, in process: the canonical calls rs274 prints, read
// into moves (machine/rs274_reader.hpp parse_rs274_calls). The gcode_rs274 harness runs rs274 itself
// (a process per input, a few inputs a second); this one reaches the same parsing at libFuzzer's
// speed. The first byte is rs274's exit status (0 below 200, else byte - 199; 255: killed by SIGKILL),
// the rest its output. Seeds: rs274's real output on the gcode_rs274 seeds and on a refused program.
#include "fuzz/fuzz_input.hpp"
#include "machine/rs274_reader.hpp"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const int status = data[0] == 255 ? 128 + 9 : data[0] >= 200 ? data[0] - 199 : 0;
  const std::string origin = "fuzz.ngc";
  drom::fuzz::expect_clean(
      [&] {
        const auto program = drom::machine::parse_rs274_calls(drom::fuzz::as_text(data + 1, size - 1), status, origin);
        drom::fuzz::require(status == 0, "a program rs274 refused (status " + std::to_string(status) + ") read without an error");
        for (const auto& m : program.moves)
          drom::fuzz::require(m.start.allFinite() && m.end.allFinite() && m.centre.allFinite() && std::isfinite(m.programmed_duration()),
                              "a move with a non-finite position or duration");
      },
      origin);
  return 0;
}
