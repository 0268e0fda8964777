#pragma once
// A stop asked from outside a long job (Python's Ctrl-C, a service shutting down), as the jobs take
// it: a std::stop_token in their options, checked between stations, removal steps and loop steps.
// A job that cannot end with a partial result of its own (drom run's loop) throws StopRequested;
// what it had saved (the offline stages' checkpoints) stays resumable.
#include <stdexcept>
#include <stop_token>

namespace drom {

struct StopRequested : std::runtime_error {
  StopRequested() : std::runtime_error("stopped on request") {}
};

inline void throw_if_stop_requested(const std::stop_token& stop) {
  if (stop.stop_requested()) throw StopRequested();
}

}  // namespace drom
