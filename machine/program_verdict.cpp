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

// The worst demand along one run of consecutive cutting blocks (indices into program.blocks): the
// joints, linear in time between block ends at the programmed feeds, sampled every `h` seconds, then
// central differences. h is ten interpolation cycles: the NC cannot follow a demand on a shorter
// scale anyway (it smooths over its look-ahead), and the positions' printed rounding (1e-4 mm or
// degree) would otherwise pass for acceleration and jerk on short blocks.
void judge_run(const MachineProgram& program, const std::vector<std::size_t>& run, const Kinematics& kin, ProgramVerdict& v) {
  const Machine& m = kin.machine();
  const std::size_t ends = run.size() + 1;  // the run's start, then every block's end
  std::vector<Joints> q(ends);
  std::vector<double> t(ends, 0.0);
  q[0] = program.blocks[run.front()].start;
  for (std::size_t k = 0; k < run.size(); ++k) {
    const MachineBlock& b = program.blocks[run[k]];
    q[k + 1] = b.end;
    t[k + 1] = t[k] + b.programmed_duration;
  }
  const double h = 10 * m.interpolation_cycle;
  const std::size_t n = static_cast<std::size_t>(std::ceil(t.back() / h)) + 1;
  if (n < 2) return;
  std::vector<Joints> samples(n);
  std::vector<int> line(n, 0);
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const double ti = std::min(t.back(), static_cast<double>(i) * h);
    while (k + 2 < ends && t[k + 1] < ti) ++k;
    const double span = t[k + 1] - t[k], f = span > 0 ? std::clamp((ti - t[k]) / span, 0.0, 1.0) : 1.0;
    samples[i] = q[k] + f * (q[k + 1] - q[k]);
    line[i] = program.blocks[run[k]].line;
  }
  auto diff = [&](const std::vector<Joints>& x) {
    std::vector<Joints> d(n, Joints::Zero());
    for (std::size_t i = 0; i < n; ++i) {
      const std::size_t lo = i == 0 ? 0 : i - 1, hi = std::min(i + 1, n - 1);
      d[i] = (x[hi] - x[lo]) / (static_cast<double>(hi - lo) * h);
    }
    return d;
  };
  const std::vector<Joints> vel = diff(samples), acc = diff(vel), jerk = diff(acc);
  AxisDemand* demand[3] = {&v.velocity, &v.acceleration, &v.jerk};
  const std::vector<Joints>* derivative[3] = {&vel, &acc, &jerk};
  for (int j = 0; j < m.joint_count(); ++j) {
    const double limit[3] = {m.axes[j].velocity, m.axes[j].acceleration, m.axes[j].jerk};
    // Velocity block by block (a block's joints move linearly at its programmed feed): exact, and the
    // rounding is negligible against it.
    if (limit[0] > 0)
      for (std::size_t b = 0; b < run.size(); ++b) {
        const double r = std::abs(q[b + 1](j) - q[b](j)) / (t[b + 1] - t[b]) / limit[0];
        if (t[b + 1] > t[b] && r > v.velocity.ratio) v.velocity = {r, std::string(1, m.axes[j].name), program.blocks[run[b]].line};
      }
    for (int d = 1; d < 3; ++d) {
      if (!(limit[d] > 0)) continue;
      for (std::size_t i = 0; i < n; ++i) {
        const double r = std::abs((*derivative[d])[i](j)) / limit[d];
        if (r > demand[d]->ratio) *demand[d] = {r, std::string(1, m.axes[j].name), line[i]};
      }
    }
  }
}

}  // namespace

ProgramVerdict scan_program(const MachineProgram& program, const std::string& origin, const Kinematics& kin) {
  const Machine& m = kin.machine();
  ProgramVerdict v;
  v.origin = origin;
  for (std::size_t i = 0; i < program.blocks.size(); ++i) {
    const MachineBlock& b = program.blocks[i];
    for (int j = 0; j < m.joint_count(); ++j) {
      const double value = kin.stroke_value(j, b.end);
      if (m.axes[j].within(value, 1e-6)) continue;
      if (v.beyond_stroke_count++ >= ProgramVerdict::kKeptExcesses) continue;  // counted; a program wholly off the table keeps its memory
      char buf[160];
      std::snprintf(buf, sizeof buf, " beyond its stroke [%g, %g] %s", joint_in_program_units(m, j, m.axes[j].min), joint_in_program_units(m, j, m.axes[j].max),
                    m.axes[j].rotary ? "deg" : "mm");
      v.beyond_strokes.push_back({i, b.line, j, value,
                                  origin + ":" + std::to_string(b.line) + ": " + describe_joint_value(m, j, value) +
                                      (j == 2 && kin.tip_controlled() ? " (gauge line: Z + tool length)" : "") + buf});
    }
    if (m.rotary_count() > 0) {
      const double d = kin.singularity_distance(kin.forward(b.end).axis);
      if (d < m.singularity_cone && (v.singular_passages.empty() || v.singular_passages.back().line != b.line)) v.singular_passages.push_back({b.line, d});
    }
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
  return v;
}

ProgramVerdict judge_program(const std::string& text, const std::string& origin, const Kinematics& kin) {
  ProgramReadOptions plain;
  plain.reader = ReaderChoice::Plain;
  const MachineProgram program = to_machine_program(parse_program(text, origin, plain), kin.machine());
  ProgramVerdict v = scan_program(program, origin, kin);
  if (v.runnable() && !program.blocks.empty()) {
    const FeedPrediction p = predict_feed(program, kin);
    v.cycle_time = p.cycle_time;
    v.programmed_time = p.programmed_time;
    v.share_at_programmed_feed = p.cutting_length > 0 ? p.length_at_programmed_feed / p.cutting_length : 1.0;
  }
  return v;
}

nlohmann::json ProgramVerdict::demand_json() const {
  auto demand = [](const AxisDemand& d) { return nlohmann::json{{"ratio", d.ratio}, {"axis", d.axis}, {"line", d.line}}; };
  return {{"velocity", demand(velocity)}, {"acceleration", demand(acceleration)}, {"jerk", demand(jerk)}};
}

nlohmann::json ProgramVerdict::to_json() const {
  std::vector<std::string> first;
  for (std::size_t i = 0; i < std::min<std::size_t>(20, beyond_strokes.size()); ++i) first.push_back(beyond_strokes[i].what);
  std::vector<int> lines;
  for (const auto& p : singular_passages) lines.push_back(p.line);
  return {{"program", origin},
          {"runnable", runnable()},
          {"out_of_reach", first},
          {"out_of_reach_blocks", beyond_stroke_count},
          {"singularity_passages", singular_passages.size()},
          {"singularity_lines", lines},
          {"demand_at_programmed_feed", demand_json()},
          {"slows_down", slows_down()},
          {"cycle_time_s", cycle_time},
          {"programmed_time_s", programmed_time},
          {"share_of_cutting_length_at_programmed_feed", share_at_programmed_feed}};
}

std::string ProgramVerdict::summary_line() const {
  char buf[512];
  if (!runnable()) {
    std::snprintf(buf, sizeof buf, "%zu blocks beyond the machine's strokes (first: %s): not written as a runnable program", beyond_stroke_count,
                  beyond_strokes.front().what.c_str());
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
                part("jerk", jerk).c_str(), singular_passages.size());
  return buf;
}

}  // namespace drom::machine
