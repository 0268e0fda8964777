// drom orient: the collision-free tool-axis orientation of seed 000 on a case (paths/orient/orient_run.hpp).
#include "apps/commands.hpp"
#include "paths/orient/orient_run.hpp"
#include "support/input_error.hpp"

#include <iostream>

namespace drom::app {

int orient_command(const CommandOptions& options) {
  if (!options.case_path) throw InputError("drom orient needs a case, e.g. drom orient cases/orient_corner.toml");
  const paths::OrientCase c = paths::load_orient_case(*options.case_path, options.overrides);
  const auto result = paths::run_orient(c, {options.out, options.quiet, true, options.threads});
  if (!result.unreachable.empty())
    std::cerr << "drom orient: " << result.unreachable.size() << " poses of the corrected axis are out of the machine's reach (first: " << result.unreachable.front()
              << "); no G-code written, the rest is in " << options.out.string() << "\n";
  return result.after.collisions.empty() && result.unreachable.empty() ? 0 : 3;
}

}  // namespace drom::app
