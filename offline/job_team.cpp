#include "offline/job_team.hpp"

#include <chrono>

namespace drom::offline {

std::size_t StationWork::saved_one() { return ++saved_; }

void StationWork::fail(std::exception_ptr failure) {
  std::lock_guard<std::mutex> lock(mutex_);
  if (!failure_) failure_ = failure;
  cancelled_ = true;
  changed_.notify_all();
}

void StationWork::worker_done() {
  std::lock_guard<std::mutex> lock(mutex_);
  --running_;
  changed_.notify_all();
}

void StationWork::start(int workers) {
  std::lock_guard<std::mutex> lock(mutex_);
  running_ = workers;
}

void StationWork::wait_finished() const {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait(lock, [&] { return running_ == 0; });
}

std::exception_ptr StationWork::failure() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return failure_;
}

bool StationWork::finished() const {
  std::lock_guard<std::mutex> lock(mutex_);
  return running_ == 0;
}

void StationWork::wait(double seconds) const {
  std::unique_lock<std::mutex> lock(mutex_);
  changed_.wait_for(lock, std::chrono::duration<double>(seconds), [&] { return running_ == 0 || failure_; });
}

void SoloTeam::agree(std::exception_ptr failure) {
  if (!failure) return;
  failed_ = true;
  std::rethrow_exception(failure);  // as it was thrown (a Python exception from a callback stays one)
}

void SoloTeam::supervise(StationWork& work, const std::function<bool(std::size_t)>&) {
  work.wait_finished();
  agree(work.failure());
}

std::string on_root_then_broadcast(JobTeam& team, const std::function<std::string()>& work) {
  std::string bytes;
  std::exception_ptr failure;
  if (team.root()) {
    try {
      bytes = work();
    } catch (...) {
      failure = std::current_exception();
    }
  }
  team.agree(failure);
  return team.broadcast(std::move(bytes));
}

void on_every_rank(JobTeam& team, const std::function<void()>& work) {
  std::exception_ptr failure;
  try {
    work();
  } catch (...) {
    failure = std::current_exception();
  }
  team.agree(failure);
}

}  // namespace drom::offline
