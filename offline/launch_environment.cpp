#include "offline/launch_environment.hpp"

#include <cstdlib>

namespace drom::offline {

namespace {

int number(const char* name, int fallback) {
  const char* v = std::getenv(name);
  if (!v || !*v) return fallback;
  char* end = nullptr;
  const long n = std::strtol(v, &end, 10);
  return *end == '\0' && n >= 0 && n < 1 << 30 ? static_cast<int>(n) : fallback;
}

}  // namespace

LaunchEnvironment launch_environment() {
  LaunchEnvironment e;
  if (std::getenv("OMPI_COMM_WORLD_SIZE")) {
    e.launcher = "mpirun (OMPI_COMM_WORLD_SIZE)";
    e.rank = number("OMPI_COMM_WORLD_RANK", 0);
    e.ranks = number("OMPI_COMM_WORLD_SIZE", 0);
  } else if (std::getenv("PMI_SIZE") || std::getenv("PMI_RANK")) {
    e.launcher = "a PMI launcher (PMI_RANK)";
    e.rank = number("PMI_RANK", 0);
    e.ranks = number("PMI_SIZE", 0);
  } else if (std::getenv("PMIX_RANK")) {
    e.launcher = "a PMIx launcher (PMIX_RANK)";
    e.rank = number("PMIX_RANK", 0);
  } else {
    return e;
  }
  e.launched = true;
  return e;
}

}  // namespace drom::offline
