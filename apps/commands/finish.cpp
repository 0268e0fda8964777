// drom finish: finishing paths on a free-form surface that take the least time under a scallop bound
// (paths/finish/finish_run.hpp).
#include "apps/commands.hpp"
#include "paths/finish/finish_run.hpp"
#include "support/input_error.hpp"

#include <cstdio>

namespace drom::app {

int finish_command(const CommandOptions& options) {
  if (!options.case_path) throw InputError("drom finish needs a finishing case, e.g. drom finish cases/rubio.toml");
  const paths::FinishCase c = paths::load_finish_case(*options.case_path, options.overrides);
  const auto s = paths::run_finish(c, {options.out, options.quiet, options.threads, options.resume});
  if (s.contains("program_refused")) {
    std::fprintf(stderr, "drom finish: no runnable program: %s; the rest is in %s\n", s["program_refused"].get<std::string>().c_str(), options.out.string().c_str());
    return 3;
  }
  return 0;
}

}  // namespace drom::app
