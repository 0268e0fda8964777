#pragma once
// The processes that run one offline job together: this process alone, or the ranks of an MPI job
// (`mpirun -np N drom offline ...`, offline/process_team.hpp). The job speaks to the others only here.
//
// Failures never leave a rank waiting. Every collective step starts with agree(): each rank says
// whether it failed, and if one did, every rank throws the same error (the lowest failing rank's,
// InputError if it was one) and the ranks say nothing more to each other. While the stations are
// solved, supervise() exchanges the ranks' progress a few times a second, so a failure or a stop
// reaches every rank after the stations in progress.
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <exception>
#include <functional>
#include <mutex>
#include <string>
#include <vector>

namespace drom::offline {

// The stations one rank solves, as its workers and the team's supervision see them.
class StationWork {
 public:
  // From a worker: one more station saved (all outputs). Returns the rank's count.
  std::size_t saved_one();
  // From a worker: it stops on this (its own failure is kept: the first one).
  void fail(std::exception_ptr failure);
  // From a worker when it has nothing left to do.
  void worker_done();
  // Workers stop after the stations in progress (another rank failed, or the job is asked to stop).
  void cancel() { cancelled_ = true; }
  bool cancelled() const { return cancelled_; }

  std::size_t saved() const { return saved_; }
  std::exception_ptr failure() const;
  bool finished() const;  // every worker done
  // Waits until every worker is done, a worker failed, or `seconds` have passed.
  void wait(double seconds) const;
  void wait_finished() const;
  void start(int workers);

 private:
  std::atomic<std::size_t> saved_{0};
  std::atomic<bool> cancelled_{false};
  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  int running_ = 0;
  std::exception_ptr failure_;
};

class JobTeam {
 public:
  virtual ~JobTeam() = default;
  virtual int rank() const = 0;
  virtual int size() const = 0;
  bool root() const { return rank() == 0; }
  // Where this rank runs, for messages: "rank 1 of 4 (node12)".
  virtual std::string where() const = 0;

  // Every rank, in the same order: `failure` is this rank's (null: none). Throws on every rank if any
  // rank failed. After that throw, failed() is true and the team must not be used again.
  virtual void agree(std::exception_ptr failure) = 0;
  // After an agree(): rank 0's bytes, on every rank.
  virtual std::string broadcast(std::string bytes) = 0;
  // After an agree(): every rank's text, in rank order, on rank 0 (empty elsewhere).
  virtual std::vector<std::string> gather(const std::string& text) = 0;
  // While this rank's workers run `work`, until every rank's are done: rank 0 calls report(saved)
  // with the whole job's count of saved stations whenever it grows (false: stop the job after the
  // stations in progress). Then agree()s on the workers' failures. Solo: report is not called (the
  // workers report themselves, station by station).
  virtual void supervise(StationWork& work, const std::function<bool(std::size_t saved)>& report) = 0;
  // Workers of this rank call the progress report themselves (one process: synchronous, per station).
  bool reports_per_station() const { return size() == 1; }

  bool failed() const { return failed_; }

 protected:
  bool failed_ = false;
};

// This process alone.
class SoloTeam final : public JobTeam {
 public:
  int rank() const override { return 0; }
  int size() const override { return 1; }
  std::string where() const override { return "this process"; }
  void agree(std::exception_ptr failure) override;
  std::string broadcast(std::string bytes) override { return bytes; }
  std::vector<std::string> gather(const std::string& text) override { return {text}; }
  void supervise(StationWork& work, const std::function<bool(std::size_t)>& report) override;
};

// Runs `work` on rank 0, then hands its bytes to every rank (rank 0's failure stops every rank).
std::string on_root_then_broadcast(JobTeam& team, const std::function<std::string()>& work);
// Runs `work` on every rank, then agree()s on the failures.
void on_every_rank(JobTeam& team, const std::function<void()>& work);

}  // namespace drom::offline
