#include "machine/machine_definition.hpp"

#include "machine/shipped_machines.hpp"
#include "support/input_error.hpp"
#include "support/toml_reader.hpp"

#include <Eigen/Geometry>

#include <cmath>
#include <filesystem>
#include <limits>
#include <numbers>

namespace drom::machine {

namespace {

constexpr double kDegree = std::numbers::pi / 180;

Eigen::Vector3d vector3(TomlReader& r, const std::string& key, std::optional<Eigen::Vector3d> fallback = std::nullopt) {
  std::optional<std::vector<double>> fb;
  if (fallback) fb = std::vector<double>{fallback->x(), fallback->y(), fallback->z()};
  const auto v = r.reals(key, Range{}, fb);
  if (v.size() != 3) r.fail(key, "expected 3 numbers [x, y, z], got " + std::to_string(v.size()));
  return {v[0], v[1], v[2]};
}

AxisLimits read_axis(TomlReader& r, char name, bool rotary) {
  const std::string k = std::string("axes.") + name + ".";
  AxisLimits a;
  a.name = name;
  a.rotary = rotary;
  const double unit = rotary ? kDegree : 1.0;
  a.continuous = rotary && r.boolean(k + "continuous", false);
  if (a.continuous) {
    if (r.has(k + "stroke")) r.fail(k + "stroke", "a continuous axis has no stroke: remove `stroke` or set continuous = false");
    a.min = -std::numeric_limits<double>::infinity();
    a.max = std::numeric_limits<double>::infinity();
  } else {
    const auto s = r.reals(k + "stroke", Range{});
    if (s.size() != 2 || !(s[0] < s[1])) r.fail(k + "stroke", "expected [min, max] with min < max");
    a.min = s[0] * unit;
    a.max = s[1] * unit;
  }
  a.velocity = r.real(k + "velocity", Range::positive()) * unit;
  a.acceleration = r.real(k + "acceleration", Range::positive()) * unit;
  a.jerk = r.real(k + "jerk", Range::positive()) * unit;
  return a;
}

}  // namespace

const char* chain_name(KinematicChain chain) {
  switch (chain) {
    case KinematicChain::ThreeAxis: return "three_axis";
    case KinematicChain::TableTable: return "table_table";
    case KinematicChain::HeadHead: return "head_head";
    case KinematicChain::TableHead: return "table_head";
  }
  return "?";
}

int Machine::joint_of(char letter) const {
  for (int j = 0; j < joint_count(); ++j)
    if (axes[j].name == letter) return j;
  return -1;
}

std::string Machine::rotary_letters() const {
  std::string s;
  for (int j = 3; j < joint_count(); ++j) s += axes[j].name;
  return s;
}

Machine parse_machine(const std::string& text, const std::string& origin, const std::vector<std::string>& overrides) {
  TomlReader r(text, origin, overrides);
  Machine m;
  m.origin = origin;
  m.name = r.text("name");
  m.description = r.text("description", std::string());
  const std::string chain = r.choice("kinematics", {"three_axis", "table_table", "head_head", "table_head"});
  m.chain = chain == "three_axis"    ? KinematicChain::ThreeAxis
            : chain == "table_table" ? KinematicChain::TableTable
            : chain == "head_head"   ? KinematicChain::HeadHead
                                     : KinematicChain::TableHead;

  for (char c : {'X', 'Y', 'Z'}) m.axes.push_back(read_axis(r, c, false));
  std::vector<std::string> letters;
  if (m.chain == KinematicChain::ThreeAxis) {
    if (r.has("rotary_axes") && !r.strings("rotary_axes").empty()) r.fail("rotary_axes", "a three_axis machine has no rotary axes");
  } else {
    letters = r.strings("rotary_axes");
    if (letters.size() != 2) r.fail("rotary_axes", "expected two rotary axes from the base outward, e.g. [\"A\", \"C\"]");
    if (letters[0] == letters[1]) r.fail("rotary_axes", "the two rotary axes must differ");
  }
  int on_table = 0;
  for (const auto& l : letters) {
    if (l != "A" && l != "B" && l != "C") r.fail("rotary_axes", "rotary axes are named A, B or C, got \"" + l + "\"");
    const std::string k = "axes." + l + ".";
    RotaryJoint joint;
    joint.on_table = r.choice(k + "on", {"table", "head"}) == "table";
    on_table += joint.on_table;
    const Eigen::Vector3d d = vector3(r, k + "direction");
    if (!(d.norm() > 1e-9)) r.fail(k + "direction", "the axis direction must not be zero");
    joint.direction = d.normalized();
    joint.point = vector3(r, k + "point", Eigen::Vector3d::Zero());
    m.rotary.push_back(joint);
    m.axes.push_back(read_axis(r, l[0], true));
  }
  if (m.chain != KinematicChain::ThreeAxis) {
    const int expected = m.chain == KinematicChain::TableTable ? 2 : m.chain == KinematicChain::HeadHead ? 0 : 1;
    if (on_table != expected)
      r.fail("axes." + letters[0] + ".on", std::string("a ") + chain + " machine has " + std::to_string(expected) +
                                               " rotary axis/axes on the table, this file puts " + std::to_string(on_table) + " there");
    if (m.rotary[0].direction.cross(m.rotary[1].direction).norm() < 1e-6)
      r.fail("axes." + letters[1] + ".direction", "the two rotary axes are parallel: they cannot orient the tool");
    if (m.chain == KinematicChain::TableHead && !m.rotary[0].on_table)
      r.fail("rotary_axes", "a table_head machine lists its table axis first (the base), then its head axis");
  }

  m.interpolation_cycle = r.real("control.interpolation_cycle", Range::open_closed(0, 0.1), 0.002);
  const std::string junction = r.choice("control.junction", {"blend", "smooth", "exact_stop"}, std::string("blend"));
  m.junction = junction == "blend" ? JunctionMode::Blend : junction == "smooth" ? JunctionMode::Smooth : JunctionMode::ExactStop;
  m.junction_tolerance = r.real("control.junction_tolerance", Range::non_negative(), 0.01);
  m.junction_tolerance_rotary = r.real("control.junction_tolerance_rotary", Range::non_negative(), 0.01) * kDegree;
  m.singularity_cone = r.real("control.singularity_cone", Range::open_closed(0, 45), 1.0) * kDegree;
  const bool head = m.chain == KinematicChain::HeadHead || m.chain == KinematicChain::TableHead;
  if (head) m.pivot_length = r.real("head.pivot_length", Range::non_negative());
  else if (r.has("head.pivot_length")) r.fail("head.pivot_length", std::string("a ") + chain + " machine has no head pivot");
  m.tool_length = r.real("setup.tool_length", Range::positive(), 100);
  m.part_origin = vector3(r, "setup.part_origin", Eigen::Vector3d::Zero());
  const AxisLimits& z = m.axes[2];
  const double highest = head ? z.max : z.max - m.tool_length;  // Z's stroke bounds the gauge line on tip-controlled chains
  const double lowest = head ? z.min : z.min - m.tool_length;
  // A tool too long for the stroke is refused where it is mounted (its message names the stroke).
  m.safe_z = highest > lowest ? r.real("setup.safe_z", Range::closed(lowest, highest), std::max(lowest, highest - 1)) : highest;
  r.finish();
  return m;
}

Machine read_machine(const std::string& path, const std::vector<std::string>& overrides) {
  return parse_machine(read_input_file(path, "machine file"), path, overrides);
}

std::vector<std::string> shipped_machine_names() {
  std::vector<std::string> names;
  for (const auto& [name, text] : kShippedMachines) names.emplace_back(name);
  return names;
}

Machine load_machine(const std::string& path_or_name, const std::vector<std::string>& overrides) {
  if (std::filesystem::exists(path_or_name)) return read_machine(path_or_name, overrides);
  for (const auto& [name, text] : kShippedMachines)
    if (path_or_name == name) return parse_machine(text, "<shipped machine " + std::string(name) + ">", overrides);
  std::string known;
  for (const auto& n : shipped_machine_names()) known += (known.empty() ? "" : ", ") + n;
  throw InputError(path_or_name + ": no such machine file, nor a shipped machine (" + known + ")");
}

}  // namespace drom::machine
