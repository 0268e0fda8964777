// Harness: a G-code program, 3- or 5-axis, in drom's plain subset (machine/gcode_reader.hpp); then
// on the 5-axis machine (machine/machine_program.hpp), and as the offline job reads a pocket program
// (levelset/gcode.hpp) with its timeline. A program outside the plain subset is refused here the way
// drom hands it to LinuxCNC's interpreter (harness gcode_rs274). Seeds: the shipped cases' toolpaths
// as G-code, a 5-axis program written by drom's post-processor, inch and helical programs.
#include "fuzz/fuzz_input.hpp"
#include "levelset/gcode.hpp"
#include "machine/gcode_reader.hpp"
#include "machine/machine_definition.hpp"
#include "machine/machine_program.hpp"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static const drom::machine::Machine five_axis = drom::machine::load_machine("ucp710_like");
  const std::string origin = "fuzz.nc";
  const std::string text = drom::fuzz::as_text(data, size);
  bool plain = false;
  drom::fuzz::expect_clean(
      [&] {
        drom::machine::NcProgram program;
        try {
          program = drom::machine::parse_plain_gcode(text, origin);
        } catch (const drom::machine::OutsidePlainSubset&) {
          return;  // drom asks rs274 (gcode_rs274)
        }
        plain = true;
        for (const auto& m : program.moves)
          drom::fuzz::require(m.start.allFinite() && m.end.allFinite() && m.centre.allFinite() && std::isfinite(m.feed) && std::isfinite(m.programmed_duration()) &&
                                  m.programmed_duration() >= 0,
                              "a move with a non-finite position, feed or duration");
        const auto on_machine = drom::machine::to_machine_program(program, five_axis);
        for (const auto& b : on_machine.blocks)
          drom::fuzz::require(drom::machine::block_joints_at(b, 0.5).allFinite() && std::isfinite(b.programmed_duration), "a block with non-finite joints");
      },
      origin);
  if (!plain) return 0;
  drom::fuzz::expect_clean(
      [&] {
        const auto path = drom::levelset::parse_gcode(text, origin);
        const drom::levelset::PathTimeline timeline(path);
        drom::fuzz::require(std::isfinite(timeline.duration()) && timeline.duration() >= 0, "a program whose duration is not a finite time");
      },
      origin);
  return 0;
}
