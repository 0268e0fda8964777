#pragma once
// The team this process was started in: the ranks of an MPI job when a launcher started it
// (OpenMPI's mpirun, or srun/mpiexec through PMI or PMIx), otherwise this process alone. MPI is
// initialised here, only under a launcher (a plain `drom offline` never touches MPI), with threads
// "funneled": only the thread that made the team calls MPI. It is finalised when the team goes.
//
// The only code of drom that knows MPI. It is its own library, in two versions (DROM_MPI on or off,
// docs/distributed.md): with MPI, process_team_mpi.cpp; without, process_team_solo.cpp, which
// refuses to run as one of several ranks rather than have every rank do the whole job.
#include "offline/job_team.hpp"

#include <memory>

namespace drom::offline {

// Throws InputError when started as one of several ranks by a drom built without MPI.
std::unique_ptr<JobTeam> join_launched_team();

// Whether this drom was built with MPI (for --version and summary.json).
bool built_with_mpi();

}  // namespace drom::offline
