// Harness: a G-code program (levelset/gcode.hpp), and the timeline the offline job builds on what it
// reads. Seeds: the shipped cases' toolpaths written as G-code.
#include "fuzz/fuzz_input.hpp"
#include "levelset/gcode.hpp"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string origin = "fuzz.nc";
  drom::fuzz::expect_clean(
      [&] {
        const auto path = drom::levelset::parse_gcode(drom::fuzz::as_text(data, size), origin);
        const drom::levelset::PathTimeline timeline(path);
        drom::fuzz::require(std::isfinite(timeline.duration()) && timeline.duration() >= 0, "a program whose duration is not a finite time");
      },
      origin);
  return 0;
}
