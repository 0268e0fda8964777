#include "machine/program_clock.hpp"

#include "support/input_error.hpp"

#include <algorithm>
#include <stdexcept>

namespace drom::machine {

ProgramClock::ProgramClock(const Eigen::MatrixXd& path, const Machine& machine, double feed_override) {
  if (path.cols() != 4 || path.rows() < 2) throw std::invalid_argument("ProgramClock: the path needs at least two waypoints (x, y, z, program time)");
  if (machine.rotary_count() != 0) throw std::invalid_argument("ProgramClock: the path is a 3-axis tool-tip path; machine " + machine.name + " has rotary axes");
  if (!(feed_override > 0)) throw std::invalid_argument("ProgramClock: the feed override must be positive");
  program_times_ = path.col(3);
  MachineProgram program;
  for (Eigen::Index i = 0; i + 1 < path.rows(); ++i) {
    const double span = path(i + 1, 3) - path(i, 3);
    if (!(span >= 0)) throw std::invalid_argument("ProgramClock: program times decrease at waypoint " + std::to_string(i + 1));
    MachineBlock b;
    b.start.head<3>() = path.row(i).head<3>().transpose() + machine.part_origin;
    b.end.head<3>() = path.row(i + 1).head<3>().transpose() + machine.part_origin;
    const bool still = (b.end - b.start).norm() < 1e-12;
    b.type = still ? MoveType::Dwell : MoveType::Linear;
    b.programmed_duration = span / feed_override;
    b.line = static_cast<int>(i) + 1;
    if (!still && !(span > 0)) throw std::invalid_argument("ProgramClock: segment " + std::to_string(i) + " moves in no program time");
    program.blocks.push_back(b);
  }
  prediction_ = predict_feed(program, Kinematics(machine));
}

double ProgramClock::program_time(double real) const {
  const auto& blocks = prediction_.blocks;
  if (real <= 0) return program_times_[0];
  if (real >= prediction_.cycle_time) return program_times_[program_times_.size() - 1];
  // The last block started by `real` (blocks are in time order; a dwell's own interval is its hold).
  const auto it = std::upper_bound(blocks.begin(), blocks.end(), real, [](double t, const BlockPrediction& b) { return t < b.t_start; });
  const std::size_t i = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, it - blocks.begin() - 1));
  const BlockPrediction& b = blocks[i];
  double f = 0;
  if (b.length > 0) f = (prediction_.at_time(real).s - b.s_start) / b.length;
  else if (b.duration > 0) f = (real - b.t_start) / b.duration;
  f = std::clamp(f, 0.0, 1.0);
  const auto k = static_cast<Eigen::Index>(i);
  return program_times_[k] + f * (program_times_[k + 1] - program_times_[k]);
}

double ProgramClock::real_time(double program) const {
  const Eigen::Index n = program_times_.size();
  if (program <= program_times_[0]) return 0;
  if (program >= program_times_[n - 1]) return prediction_.cycle_time;
  const auto it = std::upper_bound(program_times_.data(), program_times_.data() + n, program);
  const auto k = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, it - program_times_.data() - 1));
  const BlockPrediction& b = prediction_.blocks[k];
  const double span = program_times_[static_cast<Eigen::Index>(k) + 1] - program_times_[static_cast<Eigen::Index>(k)];
  const double f = span > 0 ? (program - program_times_[static_cast<Eigen::Index>(k)]) / span : 0;
  if (b.length > 0) {
    // The time the tool reaches that point of the block: on the block's own stretch.
    return std::clamp(prediction_.time_at(b.s_start + f * b.length), b.t_start, b.t_start + b.duration);
  }
  return b.t_start + f * b.duration;
}

}  // namespace drom::machine
