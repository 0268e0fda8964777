// drom machine: a program on a machine (machine/program_check.hpp).
#include "apps/commands.hpp"
#include "machine/program_check.hpp"
#include "support/input_error.hpp"

#include <cstdio>

namespace drom::app {

int machine_command(const CommandOptions& options) {
  if (!options.case_path) throw InputError("drom machine needs a program: drom machine PROGRAM --machine FILE");
  machine::ProgramCheckOptions o;
  o.program = *options.case_path;
  o.machine = options.machine;
  o.machine_overrides = options.overrides;
  o.out = options.out;
  o.sample_period = options.sample_period;
  o.read.reader = options.reader == "plain" ? machine::ReaderChoice::Plain : options.reader == "rs274" ? machine::ReaderChoice::Rs274 : machine::ReaderChoice::Automatic;
  for (const auto& td : options.tool_diameters) {
    const auto eq = td.find('=');
    try {
      if (eq == std::string::npos) throw std::invalid_argument(td);
      o.read.rs274.tool_diameters[std::stoi(td.substr(0, eq))] = std::stod(td.substr(eq + 1));
    } catch (const std::exception&) {
      throw InputError("--tool-diameter '" + td + "': expected T=D, a tool number and its diameter in mm");
    }
  }
  for (const auto& p : options.subroutine_paths) o.read.rs274.subroutine_paths.emplace_back(p);
  const auto s = machine::check_program(o);
  if (options.quiet) return 0;
  std::printf("drom machine: %s on %s (%s, read by %s) -> %s\n", o.program.string().c_str(), s["machine"]["name"].get<std::string>().c_str(),
              s["machine"]["kinematics"].get<std::string>().c_str(), s["reader"].get<std::string>().c_str(), o.out.string().c_str());
  if (s["no_motion"].get<bool>()) {
    std::printf("  no move: %s (cycle time 0 s)\n", s["no_motion_reason"].get<std::string>().c_str());
    return 0;
  }
  std::printf("  blocks                       %zu\n", s["blocks"].get<std::size_t>());
  std::printf("  cycle time                   %.3f s (%.3f s at the programmed feed: x%.3f)\n", s["cycle_time_s"].get<double>(), s["programmed_time_s"].get<double>(),
              s["cycle_time_over_programmed"].get<double>());
  std::printf("  cutting length               %.1f mm, %.1f %% of it at the programmed feed\n", s["cutting_length_mm"].get<double>(),
              100 * s["share_of_cutting_length_at_programmed_feed"].get<double>());
  for (const auto& [axis, q] : s["saturated_length_mm"].items()) {
    const double v = q["velocity"], a = q["acceleration"], j = q["jerk"];
    if (v + a + j > 0) std::printf("  held by %-3s                  velocity %.1f mm, acceleration %.1f mm, jerk %.1f mm\n", axis.c_str(), v, a, j);
  }
  for (const char* quantity : {"velocity", "acceleration", "jerk"}) {
    const auto& d = s["demand_at_programmed_feed"][quantity];
    if (!d["axis"].get<std::string>().empty())
      std::printf("  demand at the programmed feed %-12s %.3g x the limit (%s, line %d)\n", quantity, d["ratio"].get<double>(), d["axis"].get<std::string>().c_str(),
                  d["line"].get<int>());
  }
  std::printf("  singularity passages         %zu\n", s["singularity_passages"].size());
  if (s["start_assumed"].get<bool>()) std::printf("  note: the first move cuts from an unknown position; it is timed from the program origin\n");
  return 0;
}

}  // namespace drom::app
