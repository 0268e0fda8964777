#pragma once
// What a launcher tells the processes it starts, through their environment: OpenMPI's mpirun
// (OMPI_COMM_WORLD_*), PMIx (PMIX_RANK: srun --mpi=pmix, OpenMPI 4), PMI (PMI_RANK/PMI_SIZE: srun
// --mpi=pmi2, MPICH's hydra). A Slurm array task is not a launch: it runs one process.
#include <string>

namespace drom::offline {

struct LaunchEnvironment {
  bool launched = false;
  std::string launcher;  // which variables said so, for messages
  int rank = 0;
  int ranks = 0;         // 0: not told (PMIx gives the rank only)
};

LaunchEnvironment launch_environment();

}  // namespace drom::offline
