#include "machine/post_processor.hpp"

#include "support/input_error.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>

namespace drom::machine {

std::string write_machine_gcode(const MachineProgram& program, const Machine& m, const PostOptions& options) {
  std::string out;
  char buf[512];
  const bool five_axis = m.rotary_count() > 0;
  const bool head = m.chain == KinematicChain::HeadHead || m.chain == KinematicChain::TableHead;
  const double tolerance = options.blend_tolerance >= 0 ? options.blend_tolerance : m.junction_tolerance;
  out += "%\n(" + options.title + ")\n";
  std::snprintf(buf, sizeof buf, "(machine %s: %s%s%s; written by drom's post-processor)\n", m.name.c_str(), chain_name(m.chain),
                five_axis ? ", rotary axes " : "", m.rotary_letters().c_str());
  out += buf;
  out += head ? "(X Y Z: the head's pivot, tool length included; A B C in degrees)\n" : "(X Y Z: the tool tip, tool length by G43)\n";
  if (m.junction == JunctionMode::ExactStop) std::snprintf(buf, sizeof buf, "G21 G90 G17 G40 G94 G61.1\n");
  else std::snprintf(buf, sizeof buf, "G21 G90 G17 G40 G94 G64 P%.4f\n", tolerance);
  out += buf;
  std::snprintf(buf, sizeof buf, "T%d M6\n%s\n", options.tool, head ? "G49" : ("G43 H" + std::to_string(options.tool)).c_str());
  out += buf;
  if (options.spindle_speed > 0) {
    std::snprintf(buf, sizeof buf, "S%.0f M3\n", options.spindle_speed);
    out += buf;
  }
  auto axes = [&](const Joints& q) {
    std::string words;
    for (int j = 0; j < m.joint_count(); ++j) {
      char w[48];
      std::snprintf(w, sizeof w, " %c%.4f", m.axes[j].name, joint_in_program_units(m, j, q[j]));
      words += w;
    }
    return words;
  };
  bool inverse_time = false;
  double feed = -1;
  if (!program.blocks.empty()) out += "G0" + axes(program.blocks.front().start) + "\n";
  for (const MachineBlock& b : program.blocks) {
    if (b.type == MoveType::Dwell) {
      std::snprintf(buf, sizeof buf, "G4 P%.4f\n", b.programmed_duration);
      out += buf;
      continue;
    }
    if (b.type == MoveType::Arc) throw std::logic_error("write_machine_gcode: arcs are written by levelset::write_gcode");
    if (b.type == MoveType::Rapid) {
      out += (inverse_time ? "G94 G0" : "G0") + axes(b.end) + "\n";
      inverse_time = false;
      continue;
    }
    if (!(b.programmed_duration > 0)) throw std::logic_error("write_machine_gcode: a cutting block without a duration");
    if (five_axis) {
      // Inverse time: F is the number of such blocks per minute.
      std::snprintf(buf, sizeof buf, "%sG1%s F%.6f\n", inverse_time ? "" : "G93 ", axes(b.end).c_str(), 60.0 / b.programmed_duration);
      inverse_time = true;
      out += buf;
    } else {
      const double length = (b.end.head<3>() - b.start.head<3>()).norm();
      const double f = 60.0 * length / b.programmed_duration;
      if (std::abs(f - feed) > 1e-9 * f) {
        std::snprintf(buf, sizeof buf, "G1%s F%.4f\n", axes(b.end).c_str(), f);
        feed = f;
      } else {
        std::snprintf(buf, sizeof buf, "G1%s\n", axes(b.end).c_str());
      }
      out += buf;
    }
  }
  if (inverse_time) out += "G94\n";
  out += options.spindle_speed > 0 ? "M5\nM30\n%\n" : "M30\n%\n";
  return out;
}

std::string post_process(const ClProgram& cl, const Kinematics& kin, const PostOptions& options) {
  const Machine& m = kin.machine();
  const ClOnMachine on = cl_to_machine_program(cl, kin);
  if (!on.joints.violations.empty()) {
    const auto& v = on.joints.violations.front();
    std::string message = cl.origin + ":" + std::to_string(cl.points[v.pose].line) + ": cannot be machined on " + m.name + " (" + m.origin + "): " + v.what;
    if (on.joints.violations.size() > 1) message += " (and " + std::to_string(on.joints.violations.size() - 1) + " more)";
    throw InputError(message);
  }
  return write_machine_gcode(on.program, m, options);
}

}  // namespace drom::machine
