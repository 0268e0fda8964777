#pragma once
// Threads inside the numerical kernels (OpenBLAS, and the OpenMP regions CHOLMOD's supernodal
// factorization opens with a hard-coded num_threads(4)).
//
// Where the caller already runs one solve per core (station workers), or where each solve is small
// (PGD's 2D problems: ~5k unknowns, thousands of factorizations), those inner threads only sleep and
// wake: measured on the 2-core machine, two thirds of a PGD solve went to sched_yield and futex waits.
// OMP_NUM_THREADS cannot undo an explicit num_threads clause, but a zero max-active-levels makes every
// parallel region run on the calling thread. libgomp keeps max-active-levels per thread (a new
// std::thread starts from the default), so every thread that solves must hold its own scope. Both
// libraries are reached through dlsym, so nothing breaks when another BLAS or a CHOLMOD without
// OpenMP is linked.
namespace drom {

class SingleThreadedKernels {
 public:
  SingleThreadedKernels();   // kernels run on the calling thread from here...
  ~SingleThreadedKernels();  // ...until the previous settings are restored
  SingleThreadedKernels(const SingleThreadedKernels&) = delete;
  SingleThreadedKernels& operator=(const SingleThreadedKernels&) = delete;

 private:
  int blas_threads_ = -1, omp_levels_ = -1;
};

// OpenBLAS threads set to `threads` for a scope, inside a SingleThreadedKernels one: for the few
// large dense-block factorizations of a solve that runs alone (the PGD's update), where BLAS threads
// do pay. The setting is process-wide, so only a caller that is the sole solver running may use it.
class BlasThreads {
 public:
  explicit BlasThreads(int threads);
  ~BlasThreads();
  BlasThreads(const BlasThreads&) = delete;
  BlasThreads& operator=(const BlasThreads&) = delete;

 private:
  int previous_ = -1;
};

}  // namespace drom
