// What the MPI launcher told this process through its environment (CaseFarm.h), read without starting
// MPI. A file of its own, so that a program that only asks (cementsph-drr's main) does not link MPI.
#include "cementsph/parallel/CaseFarm.h"

#include <cstdlib>

namespace cementsph::parallel {

namespace {
int environmentInt(const char* name, int otherwise) {
  const char* value = std::getenv(name);
  if (!value || !*value) return otherwise;
  char* end = nullptr;
  const long v = std::strtol(value, &end, 10);
  return (end && *end == '\0' && v >= 0 && v < (1L << 30)) ? int(v) : otherwise;
}

} // namespace

// Open MPI's mpirun sets OMPI_COMM_WORLD_*; PMIx launchers (Slurm's srun --mpi=pmix, prterun) PMIX_RANK;
// PMI-1/2 launchers (MPICH's Hydra, srun --mpi=pmi2) PMI_RANK and PMI_SIZE.
bool launchedByMpi() {
  return std::getenv("OMPI_COMM_WORLD_SIZE") || std::getenv("PMIX_RANK") || std::getenv("PMI_SIZE");
}

int launchedRank() {
  for (const char* name : {"OMPI_COMM_WORLD_RANK", "PMIX_RANK", "PMI_RANK"}) {
    const int r = environmentInt(name, -1);
    if (r >= 0) return r;
  }
  return 0;
}

} // namespace cementsph::parallel
