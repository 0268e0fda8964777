#include "support/kernel_threads.hpp"

#include <dlfcn.h>

namespace drom {

namespace {

template <class F>
F symbol(const char* name) {
  return reinterpret_cast<F>(dlsym(RTLD_DEFAULT, name));
}

using GetInt = int (*)();
using SetInt = void (*)(int);

}  // namespace

SingleThreadedKernels::SingleThreadedKernels() {
  if (auto get = symbol<GetInt>("openblas_get_num_threads"))
    if (auto set = symbol<SetInt>("openblas_set_num_threads")) {
      blas_threads_ = get();
      set(1);
    }
  if (auto get = symbol<GetInt>("omp_get_max_active_levels"))
    if (auto set = symbol<SetInt>("omp_set_max_active_levels")) {
      omp_levels_ = get();
      set(0);
    }
}

SingleThreadedKernels::~SingleThreadedKernels() {
  if (blas_threads_ > 0)
    if (auto set = symbol<SetInt>("openblas_set_num_threads")) set(blas_threads_);
  if (omp_levels_ >= 0)
    if (auto set = symbol<SetInt>("omp_set_max_active_levels")) set(omp_levels_);
}

BlasThreads::BlasThreads(int threads) {
  if (auto get = symbol<GetInt>("openblas_get_num_threads"))
    if (auto set = symbol<SetInt>("openblas_set_num_threads")) {
      previous_ = get();
      set(threads);
    }
}

BlasThreads::~BlasThreads() {
  if (previous_ > 0)
    if (auto set = symbol<SetInt>("openblas_set_num_threads")) set(previous_);
}

}  // namespace drom
