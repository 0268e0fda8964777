// offline/process_team.hpp with MPI (DROM_MPI on): the ranks of MPI_COMM_WORLD as a JobTeam.
#include "offline/process_team.hpp"

#include "offline/launch_environment.hpp"
#include "support/input_error.hpp"

#include <mpi.h>

#include <algorithm>
#include <array>
#include <climits>
#include <cstdint>
#include <stdexcept>

namespace drom::offline {

namespace {

// What each rank says at every exchange, as one fixed-size record, so that agree() and supervise()'s
// rounds are the same collective call: a rank that failed before a round and a rank in the round
// still meet, and both learn of the failure there.
enum Field { kStep, kFailed, kInputError, kDone, kStop, kSaved, kFields };
enum Step : std::int64_t { kAgreeStep = 1, kRoundStep = 2 };
using Record = std::array<std::int64_t, kFields>;

// Broadcasts move at most this much per call (MPI counts are ints).
constexpr std::size_t kPiece = std::size_t{1} << 30;

class MpiTeam final : public JobTeam {
 public:
  MpiTeam() {
    int provided = 0;
    MPI_Init_thread(nullptr, nullptr, MPI_THREAD_FUNNELED, &provided);
    if (provided < MPI_THREAD_FUNNELED) throw std::runtime_error("MPI: this MPI library cannot run a threaded rank (MPI_THREAD_FUNNELED)");
    // Our own communicator: nothing else in the process can match our messages.
    MPI_Comm_dup(MPI_COMM_WORLD, &comm_);
    MPI_Comm_rank(comm_, &rank_);
    MPI_Comm_size(comm_, &size_);
    char name[MPI_MAX_PROCESSOR_NAME] = {};
    int length = 0;
    MPI_Get_processor_name(name, &length);
    host_.assign(name, static_cast<std::size_t>(length));
  }
  ~MpiTeam() override {
    MPI_Comm_free(&comm_);
    MPI_Finalize();
  }

  int rank() const override { return rank_; }
  int size() const override { return size_; }
  std::string where() const override { return "rank " + std::to_string(rank_) + " of " + std::to_string(size_) + " (" + host_ + ")"; }

  void agree(std::exception_ptr failure) override {
    Record mine{};
    mine[kStep] = kAgreeStep;
    describe(failure, mine);
    settle(exchange(mine), failure);
  }

  std::string broadcast(std::string bytes) override {
    std::uint64_t n = bytes.size();
    MPI_Bcast(&n, 1, MPI_UINT64_T, 0, comm_);
    bytes.resize(n);
    for (std::size_t at = 0; at < n; at += kPiece)
      MPI_Bcast(bytes.data() + at, static_cast<int>(std::min(kPiece, n - at)), MPI_CHAR, 0, comm_);
    return bytes;
  }

  std::vector<std::string> gather(const std::string& text) override {
    if (text.size() > INT_MAX) throw std::length_error("MPI gather: more than 2 GB from one rank");
    int n = static_cast<int>(text.size());
    std::vector<int> sizes(static_cast<std::size_t>(size_)), offsets(static_cast<std::size_t>(size_));
    MPI_Gather(&n, 1, MPI_INT, sizes.data(), 1, MPI_INT, 0, comm_);
    std::string all;
    if (root()) {
      long long total = 0;
      for (int r = 0; r < size_; ++r) offsets[static_cast<std::size_t>(r)] = static_cast<int>(total), total += sizes[static_cast<std::size_t>(r)];
      if (total > INT_MAX) throw std::length_error("MPI gather: more than 2 GB in all");
      all.resize(static_cast<std::size_t>(total));
    }
    MPI_Gatherv(text.data(), n, MPI_CHAR, all.data(), sizes.data(), offsets.data(), MPI_CHAR, 0, comm_);
    std::vector<std::string> texts;
    if (root())
      for (int r = 0; r < size_; ++r) texts.push_back(all.substr(static_cast<std::size_t>(offsets[static_cast<std::size_t>(r)]), static_cast<std::size_t>(sizes[static_cast<std::size_t>(r)])));
    return texts;
  }

  void supervise(StationWork& work, const std::function<bool(std::size_t)>& report) override {
    if (size_ == 1) {  // mpirun -np 1: the workers report themselves
      work.wait_finished();
      agree(work.failure());
      return;
    }
    std::size_t reported = 0;
    bool stop = false;  // rank 0's report asked the job to stop
    for (;;) {
      work.wait(0.25);
      Record mine{};
      mine[kStep] = kRoundStep;
      mine[kDone] = work.finished();  // before the failure: a worker records its failure before it ends
      const std::exception_ptr failure = work.failure();
      describe(failure, mine);
      mine[kStop] = stop;
      mine[kSaved] = static_cast<std::int64_t>(work.saved());
      const auto all = exchange(mine);
      bool done = true, stopping = false;
      std::int64_t saved = 0;
      for (const Record& r : all) {
        if (r[kFailed] || r[kStep] != kRoundStep) {
          work.cancel();  // the workers stop after the stations in progress; the caller joins them
          settle(all, failure);
        }
        done = done && r[kDone];
        stopping = stopping || r[kStop];
        saved += r[kSaved];
      }
      if (stopping) work.cancel();
      if (root() && static_cast<std::size_t>(saved) > reported) {
        reported = static_cast<std::size_t>(saved);
        try {
          if (!report(reported)) stop = true;
        } catch (...) {
          // Every rank hears of it at the next round. After the last round there is none: every
          // station is saved, and rank 0 throwing alone would leave the others waiting, so it is dropped.
          if (!done) work.fail(std::current_exception());
        }
      }
      if (done) return;
    }
  }

 private:
  static void describe(const std::exception_ptr& failure, Record& r) {
    if (!failure) return;
    r[kFailed] = 1;
    try {
      std::rethrow_exception(failure);
    } catch (const InputError&) {
      r[kInputError] = 1;
    } catch (...) {
    }
  }

  std::vector<Record> exchange(const Record& mine) {
    std::vector<Record> all(static_cast<std::size_t>(size_));
    MPI_Allgather(mine.data(), kFields, MPI_INT64_T, all.data(), kFields, MPI_INT64_T, comm_);
    return all;
  }

  // After an exchange: if any rank failed, every rank throws the lowest failing rank's error, named
  // with its rank unless every rank failed alike. Ranks at different steps with no failure is a bug
  // of drom's, and every rank says so.
  void settle(const std::vector<Record>& all, const std::exception_ptr& failure) {
    int first = -1, failures = 0;
    bool same_step = true;
    for (int r = 0; r < size_; ++r) {
      const Record& rec = all[static_cast<std::size_t>(r)];
      same_step = same_step && rec[kStep] == all.front()[kStep];
      if (rec[kFailed]) {
        ++failures;
        if (first < 0) first = r;
      }
    }
    if (first < 0) {
      if (same_step) return;
      failed_ = true;
      throw std::logic_error("MPI ranks out of step (a drom bug): some agree while others report progress");
    }
    std::string message;
    if (rank_ == first) {
      try {
        std::rethrow_exception(failure);
      } catch (const std::exception& e) {
        message = e.what();
      } catch (...) {
        message = "unknown failure";
      }
      if (failures < size_) message = where() + ": " + message;
    }
    message = broadcast_from(first, std::move(message));
    failed_ = true;
    if (all[static_cast<std::size_t>(first)][kInputError]) throw InputError(message);
    throw std::runtime_error(message);
  }

  std::string broadcast_from(int from, std::string text) {
    std::uint64_t n = text.size();
    MPI_Bcast(&n, 1, MPI_UINT64_T, from, comm_);
    text.resize(n);
    MPI_Bcast(text.data(), static_cast<int>(std::min<std::uint64_t>(n, INT_MAX)), MPI_CHAR, from, comm_);
    return text;
  }

  MPI_Comm comm_ = MPI_COMM_NULL;
  int rank_ = 0, size_ = 1;
  std::string host_;
};

}  // namespace

std::unique_ptr<JobTeam> join_launched_team() {
  if (!launch_environment().launched) return std::make_unique<SoloTeam>();
  return std::make_unique<MpiTeam>();
}

bool built_with_mpi() { return true; }

}  // namespace drom::offline
