// SingleThreadedKernels: CHOLMOD opens OpenMP regions with a hard-coded num_threads(4); within the
// scope they must run on the calling thread, in whichever thread holds the scope (the offline job's
// station workers each hold one: libgomp keeps the setting per thread).
#include "support/kernel_threads.hpp"

#include <gtest/gtest.h>
#include <omp.h>

#include <thread>

namespace {

int team_of_four() {
  int size = 0;
#pragma omp parallel num_threads(4)
  {
#pragma omp single
    size = omp_get_num_threads();
  }
  return size;
}

}  // namespace

TEST(SingleThreadedKernels, RunsARegionOfFourOnTheCallingThreadAndRestoresOnExit) {
  const int before = team_of_four();
  {
    const drom::SingleThreadedKernels kernels;
    EXPECT_EQ(team_of_four(), 1);
  }
  EXPECT_EQ(team_of_four(), before);
}

TEST(SingleThreadedKernels, WorksInAThreadOfItsOwn) {
  const drom::SingleThreadedKernels outer;  // the main thread's scope, as the offline job holds it
  int inside = 0, after = 0;
  std::thread worker([&] {
    {
      const drom::SingleThreadedKernels kernels;
      inside = team_of_four();
    }
    after = omp_get_max_active_levels();
  });
  worker.join();
  EXPECT_EQ(inside, 1);
  EXPECT_GT(after, 0) << "the worker's own setting is restored when its scope ends";
}
