// offline/process_team.hpp for a drom built without MPI (DROM_MPI off).
#include "offline/process_team.hpp"

#include "offline/launch_environment.hpp"
#include "support/input_error.hpp"

namespace drom::offline {

std::unique_ptr<JobTeam> join_launched_team() {
  const LaunchEnvironment launch = launch_environment();
  if (launch.ranks > 1 || launch.rank > 0)
    throw InputError("this drom was built without MPI (DROM_MPI off), but " + launch.launcher + " started it as rank " + std::to_string(launch.rank) +
                     (launch.ranks > 0 ? " of " + std::to_string(launch.ranks) : "") +
                     ": every rank would compute the whole job. Run it as one process, split the stations with --stations a:b and drom merge, "
                     "or build drom with MPI (docs/distributed.md)");
  return std::make_unique<SoloTeam>();
}

bool built_with_mpi() { return false; }

}  // namespace drom::offline
