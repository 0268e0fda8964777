// drom orient: the collision-free tool-axis orientation of seed 000 on a case (paths/orient_run.hpp).
#include "apps/commands.hpp"
#include "paths/orient_run.hpp"
#include "support/input_error.hpp"

namespace drom::app {

int orient_command(const CommandOptions& options) {
  if (!options.case_path) throw InputError("drom orient needs a case, e.g. drom orient cases/orient_corner.toml");
  const paths::OrientCase c = paths::load_orient_case(*options.case_path, options.overrides);
  const auto result = paths::run_orient(c, {options.out, options.quiet, true});
  return result.after.collisions.empty() ? 0 : 3;
}

}  // namespace drom::app
