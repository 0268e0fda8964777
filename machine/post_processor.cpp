#include "machine/post_processor.hpp"

#include "support/input_error.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <cstdio>
#include <numbers>

namespace drom::machine {

double default_spindle_speed(double tool_diameter) {
  if (!(tool_diameter > 0)) return 10000;
  const double rpm = 1000 * 300 / (std::numbers::pi * tool_diameter);
  return std::clamp(std::round(rpm / 100) * 100, 1000.0, 24000.0);
}

double spindle_speed(const PostOptions& options) { return options.spindle_speed > 0 ? options.spindle_speed : default_spindle_speed(options.tool_diameter); }

// Text inside a G-code comment: no parentheses (a comment does not nest) and no line breaks.
std::string comment_text(const std::string& text) {
  std::string out;
  for (const char c : text) out += c == '(' ? '[' : c == ')' ? ']' : static_cast<unsigned char>(c) < 0x20 ? ' ' : c;
  return out;
}

std::string program_header(const PostOptions& options, const std::string& modal_line, const std::string& tool_length_line, const std::string& comments) {
  char buf[160];
  std::string out = "%\n(" + comment_text(options.title) + ")\n" + comments;
  out += "G21 G90 G17 G40 G94 G54" + (modal_line.empty() ? std::string() : " " + modal_line) + "\n";
  std::snprintf(buf, sizeof buf, "T%d M6\n", options.tool);
  out += buf;
  if (!tool_length_line.empty()) out += tool_length_line + "\n";
  std::snprintf(buf, sizeof buf, "S%.0f %s\n", spindle_speed(options), options.counter_clockwise ? "M4" : "M3");
  out += buf;
  if (options.coolant != Coolant::off) out += options.coolant == Coolant::flood ? "M8\n" : "M7\n";
  return out;
}

std::string program_end(const PostOptions& options) { return options.coolant != Coolant::off ? "M5\nM9\nM30\n%\n" : "M5\nM30\n%\n"; }

std::string write_machine_gcode(const MachineProgram& program, const Machine& m, const PostOptions& options) {
  std::string out;
  char buf[512];
  const bool five_axis = m.rotary_count() > 0;
  const bool head = m.chain == KinematicChain::HeadHead || m.chain == KinematicChain::TableHead;
  const double tolerance = options.blend_tolerance >= 0 ? options.blend_tolerance : m.junction_tolerance;
  std::snprintf(buf, sizeof buf, "(machine %s: %s%s%s; written by drom's post-processor)\n", comment_text(m.name).c_str(), chain_name(m.chain), five_axis ? ", rotary axes " : "",
                m.rotary_letters().c_str());
  std::string comments = buf;
  comments += head ? "(X Y Z: the head's pivot, tool length included; A B C in degrees)\n" : "(X Y Z: the tool tip, tool length by G43)\n";
  char modal[64];
  if (m.junction == JunctionMode::ExactStop) std::snprintf(modal, sizeof modal, "G61.1");
  else std::snprintf(modal, sizeof modal, "G64 P%.4f", tolerance);
  out += program_header(options, modal, head ? "G49" : "G43 H" + std::to_string(options.tool), comments);

  const int nj = m.joint_count();
  auto words = [&](const Joints& q, int from, int to) {
    std::string w;
    for (int j = from; j < to; ++j) {
      char one[48];
      std::snprintf(one, sizeof one, " %c%.4f", m.axes[j].name, joint_in_program_units(m, j, q[j]));
      w += one;
    }
    return w;
  };
  // The clearance plane: above every point of the program, below the safe height.
  double highest = -std::numeric_limits<double>::infinity();
  for (const MachineBlock& b : program.blocks) highest = std::max({highest, b.start[2], b.end[2]});
  if (highest > m.safe_z)
    throw InputError(program.origin + ": the program reaches Z " + std::to_string(highest) + ", above the machine's safe height (setup.safe_z = " +
                     std::to_string(m.safe_z) + " in " + m.origin + "): no height is safe to turn the rotary axes at");
  const double plane = std::min(m.safe_z, highest + options.clearance);

  bool inverse_time = false;
  double feed = -1;
  Joints at = Joints::Zero();
  bool known = false;  // where the machine stands before the first move is not known
  auto g0 = [&](const std::string& axes) {
    out += (inverse_time ? "G94 G0" : "G0") + axes + "\n";
    inverse_time = false;
  };
  auto z_to = [&](double z) {
    Joints q = at;
    q[2] = z;
    g0(words(q, 2, 3));
    at[2] = z;
  };
  auto rapid_to = [&](const Joints& target) {
    bool turns = !known;
    for (int j = 3; j < nj; ++j) turns = turns || std::abs(target[j] - at[j]) > 1e-9;
    const bool slides = !known || std::hypot(target[0] - at[0], target[1] - at[1]) > 1e-9;
    if (turns) {
      if (!known || at[2] < m.safe_z - 1e-9) z_to(m.safe_z);
      if (five_axis) g0(words(target, 3, nj));
      g0(words(target, 0, 2));
    } else if (slides) {
      const double lift = std::max({plane, at[2], target[2]});
      if (at[2] < lift - 1e-9) z_to(lift);
      g0(words(target, 0, 2));
    }
    const double z = at[2];
    at = target;
    at[2] = z;
    known = true;
    if (std::abs(target[2] - at[2]) > 1e-9) z_to(target[2]);
  };
  if (!program.blocks.empty()) rapid_to(program.blocks.front().start);
  for (const MachineBlock& b : program.blocks) {
    if (b.type == MoveType::Dwell) {
      std::snprintf(buf, sizeof buf, "G4 P%.4f\n", b.programmed_duration);
      out += buf;
      continue;
    }
    if (b.type == MoveType::Arc) throw std::logic_error("write_machine_gcode: arcs are written by levelset::write_gcode");
    if (b.type == MoveType::Rapid) {
      rapid_to(b.end);
      continue;
    }
    if (!(b.programmed_duration > 0)) throw std::logic_error("write_machine_gcode: a cutting block without a duration");
    if (five_axis) {
      // Inverse time: F is the number of such blocks per minute.
      std::snprintf(buf, sizeof buf, "%sG1%s F%.6f\n", inverse_time ? "" : "G93 ", words(b.end, 0, nj).c_str(), 60.0 / b.programmed_duration);
      inverse_time = true;
      out += buf;
    } else {
      const double length = (b.end.head<3>() - b.start.head<3>()).norm();
      const double f = 60.0 * length / b.programmed_duration;
      if (std::abs(f - feed) > 1e-9 * f) {
        std::snprintf(buf, sizeof buf, "G1%s F%.4f\n", words(b.end, 0, nj).c_str(), f);
        feed = f;
      } else {
        std::snprintf(buf, sizeof buf, "G1%s\n", words(b.end, 0, nj).c_str());
      }
      out += buf;
    }
    at = b.end;
  }
  // The end: back up to the safe height, the spindle and coolant off.
  if (known && at[2] < m.safe_z - 1e-9) z_to(m.safe_z);
  if (inverse_time) out += "G94\n";
  out += program_end(options);
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
