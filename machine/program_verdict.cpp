#include "machine/program_verdict.hpp"

#include "machine/feed_prediction.hpp"
#include "machine/machine_program.hpp"
#include "machine/program_reader.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace drom::machine {

namespace {

// The worst demand along one run of consecutive cutting blocks (indices into program.blocks).
void judge_run(const MachineProgram& program, const std::vector<std::size_t>& run, const Kinematics& kin, ProgramVerdict& v) {
  const Machine& m = kin.machine();
  const std::size_t n = run.size() + 1;  // the run's start, then every block's end
  std::vector<Joints> q(n);
  std::vector<double> t(n, 0.0);  // time along the run at the programmed feeds
  std::vector<int> line(n, 0);
  q[0] = program.blocks[run.front()].start;
  line[0] = program.blocks[run.front()].line;
  for (std::size_t k = 0; k < run.size(); ++k) {
    const MachineBlock& b = program.blocks[run[k]];
    q[k + 1] = b.end;
    t[k + 1] = t[k] + b.programmed_duration;
    line[k + 1] = b.line;
  }
  if (n < 2) return;
  auto diff = [&](const std::vector<Joints>& x) {
    std::vector<Joints> d(n, Joints::Zero(m.joint_count()));
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t lo = i == 0 ? 0 : i - 1, hi = std::min(i + 1, n - 1);
      if (t[hi] > t[lo]) d[i] = (x[hi] - x[lo]) / (t[hi] - t[lo]);
    }
    return d;
  };
  const std::vector<Joints> vel = diff(q), acc = diff(vel), jerk = diff(acc);
  AxisDemand* demand[3] = {&v.velocity, &v.acceleration, &v.jerk};
  const std::vector<Joints>* derivative[3] = {&vel, &acc, &jerk};
  for (int j = 0; j < m.joint_count(); ++j) {
    const double limit[3] = {m.axes[j].velocity, m.axes[j].acceleration, m.axes[j].jerk};
    for (int d = 0; d < 3; ++d) {
      if (!(limit[d] > 0)) continue;
      for (std::size_t i = 0; i < n; ++i) {
        const double r = std::abs((*derivative[d])[i](j)) / limit[d];
        if (r > demand[d]->ratio) *demand[d] = {r, std::string(1, m.axes[j].name), line[i]};
      }
    }
  }
}

}  // namespace

ProgramVerdict judge_program(const std::string& text, const std::string& origin, const Kinematics& kin) {
  const Machine& m = kin.machine();
  ProgramVerdict v;
  v.origin = origin;
  ProgramReadOptions plain;
  plain.reader = ReaderChoice::Plain;
  const MachineProgram program = to_machine_program(parse_program(text, origin, plain), m);
  for (const MachineBlock& b : program.blocks) {
    for (int j = 0; j < m.joint_count(); ++j) {
      const double value = kin.stroke_value(j, b.end);
      if (m.axes[j].within(value, 1e-6)) continue;
      if (v.out_of_reach_count++ < 20) {
        char buf[160];
        std::snprintf(buf, sizeof buf, ": %s beyond its stroke [%g, %g] %s", describe_joint_value(m, j, value).c_str(), joint_in_program_units(m, j, m.axes[j].min),
                      joint_in_program_units(m, j, m.axes[j].max), m.axes[j].rotary ? "deg" : "mm");
        v.out_of_reach.push_back(origin + ":" + std::to_string(b.line) + buf);
      }
    }
    if (m.rotary_count() > 0 && kin.singularity_distance(kin.forward(b.end).axis) < m.singularity_cone &&
        (v.singularity_lines.empty() || v.singularity_lines.back() != b.line))
      v.singularity_lines.push_back(b.line);
  }
  std::vector<std::size_t> run;
  for (std::size_t i = 0; i <= program.blocks.size(); ++i) {
    const bool cutting = i < program.blocks.size() && (program.blocks[i].type == MoveType::Linear || program.blocks[i].type == MoveType::Arc) &&
                         program.blocks[i].programmed_duration > 0;
    if (cutting) {
      run.push_back(i);
    } else if (!run.empty()) {
      judge_run(program, run, kin, v);
      run.clear();
    }
  }
  if (v.runnable() && !program.blocks.empty()) {
    const FeedPrediction p = predict_feed(program, kin);
    v.cycle_time = p.cycle_time;
    v.programmed_time = p.programmed_time;
    v.share_at_programmed_feed = p.cutting_length > 0 ? p.length_at_programmed_feed / p.cutting_length : 1.0;
  }
  return v;
}

nlohmann::json ProgramVerdict::to_json() const {
  auto demand = [](const AxisDemand& d) { return nlohmann::json{{"ratio", d.ratio}, {"axis", d.axis}, {"line", d.line}}; };
  return {{"program", origin},
          {"runnable", runnable()},
          {"out_of_reach", out_of_reach},
          {"out_of_reach_blocks", out_of_reach_count},
          {"singularity_passages", singularity_lines.size()},
          {"singularity_lines", singularity_lines},
          {"demand_at_programmed_feed", {{"velocity", demand(velocity)}, {"acceleration", demand(acceleration)}, {"jerk", demand(jerk)}}},
          {"slows_down", slows_down()},
          {"cycle_time_s", cycle_time},
          {"programmed_time_s", programmed_time},
          {"share_of_cutting_length_at_programmed_feed", share_at_programmed_feed}};
}

std::string ProgramVerdict::summary_line() const {
  char buf[512];
  if (!runnable()) {
    std::snprintf(buf, sizeof buf, "%zu blocks beyond the machine's strokes (first: %s): not written as a runnable program", out_of_reach_count,
                  out_of_reach.front().c_str());
    return buf;
  }
  auto part = [](const char* what, const AxisDemand& d) {
    char p[96];
    if (d.axis.empty()) return std::string();
    std::snprintf(p, sizeof p, "%s %.3g x (%s, line %d)", what, d.ratio, d.axis.c_str(), d.line);
    return std::string(p);
  };
  std::snprintf(buf, sizeof buf, "cycle %.1f s (%.1f s at the programmed feed, %.0f %% of the cutting length at it); demand over the limits at the programmed feed: %s, %s, %s; %zu singularity passages",
                cycle_time, programmed_time, 100 * share_at_programmed_feed, part("velocity", velocity).c_str(), part("acceleration", acceleration).c_str(),
                part("jerk", jerk).c_str(), singularity_lines.size());
  return buf;
}

}  // namespace drom::machine
