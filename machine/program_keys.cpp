#include "machine/program_keys.hpp"

namespace drom::machine {

PostOptions read_program_keys(TomlReader& r, PostOptions o) {
  o.tool = static_cast<int>(r.integer("program.tool_number", 1, 999, o.tool));
  o.spindle_speed = r.real("program.spindle_speed", Range::closed(0, 200000), o.spindle_speed);
  o.counter_clockwise = r.choice("program.spindle", {"cw", "ccw"}, std::string(o.counter_clockwise ? "ccw" : "cw")) == "ccw";
  const std::string coolant = r.choice("program.coolant", {"off", "flood", "mist"}, std::string(o.coolant == Coolant::flood ? "flood" : o.coolant == Coolant::mist ? "mist" : "off"));
  o.coolant = coolant == "flood" ? Coolant::flood : coolant == "mist" ? Coolant::mist : Coolant::off;
  o.clearance = r.real("program.clearance", Range::positive(), o.clearance);
  return o;
}

}  // namespace drom::machine
