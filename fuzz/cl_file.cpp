// Harness: cutter-location data (machine/cl_data.hpp), the same bytes as APT CLDATA and as a CSV
// table, then through the 5-axis machine's inverse kinematics. Seeds: an APT program with
// continuations and the CSV drom writes of it.
#include "fuzz/fuzz_input.hpp"
#include "machine/cl_data.hpp"
#include "machine/machine_definition.hpp"

#include <cmath>

namespace {

void check(const drom::machine::ClProgram& cl) {
  static const drom::machine::Kinematics five_axis(drom::machine::load_machine("ucp710_like"));
  for (const auto& p : cl.points)
    drom::fuzz::require(p.pose.tip.allFinite() && p.pose.axis.allFinite() && std::abs(p.pose.axis.norm() - 1) < 1e-9 && std::isfinite(p.feed) && p.feed >= 0,
                        "a CL point with a non-finite position, a tool axis not of unit length, or a bad feed");
  const auto on_machine = drom::machine::cl_to_machine_program(cl, five_axis);
  for (const auto& b : on_machine.program.blocks)
    drom::fuzz::require(b.start.allFinite() && b.end.allFinite() && std::isfinite(b.programmed_duration) && b.programmed_duration >= 0,
                        "a block with non-finite joints or duration");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string text = drom::fuzz::as_text(data, size);
  drom::fuzz::expect_clean([&] { check(drom::machine::parse_apt_cl(text, "fuzz.apt")); }, "fuzz.apt");
  drom::fuzz::expect_clean([&] { check(drom::machine::parse_cl_csv(text, "fuzz.csv")); }, "fuzz.csv");
  return 0;
}
