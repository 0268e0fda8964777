// Machine files: every key checked, with the file, line and key in the message.
#include "machine/machine_definition.hpp"
#include "support/input_error.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <numbers>

using namespace drom;
using namespace drom::machine;

namespace {

std::string message_of(const std::string& text, const std::vector<std::string>& overrides = {}) {
  try {
    parse_machine(text, "m.toml", overrides);
  } catch (const InputError& e) {
    return e.what();
  }
  return "";
}

const char* kValid = R"(name = "t"
kinematics = "table_table"
rotary_axes = ["A", "C"]
[axes.X]
stroke = [-100, 100]
velocity = 100
acceleration = 1000
jerk = 10000
[axes.Y]
stroke = [-100, 100]
velocity = 100
acceleration = 1000
jerk = 10000
[axes.Z]
stroke = [0, 300]
velocity = 100
acceleration = 1000
jerk = 10000
[axes.A]
on = "table"
direction = [1, 0, 0]
stroke = [-90, 90]
velocity = 90
acceleration = 360
jerk = 3600
[axes.C]
on = "table"
direction = [0, 0, 1]
continuous = true
velocity = 120
acceleration = 480
jerk = 4800
)";

}  // namespace

TEST(MachineFile, ShippedMachinesLoadWithTheirUnits) {
  EXPECT_EQ(shipped_machine_names().size(), 4u);
  // The flat plate's machine: vmc_3axis's dynamics on a table the 1 000 mm plate fits.
  const Machine bridge = load_machine("bridge_3axis"), vmc = load_machine("vmc_3axis");
  EXPECT_EQ(bridge.chain, KinematicChain::ThreeAxis);
  for (int j = 0; j < 3; ++j) {
    EXPECT_EQ(bridge.axes[j].velocity, vmc.axes[j].velocity);
    EXPECT_EQ(bridge.axes[j].acceleration, vmc.axes[j].acceleration);
    EXPECT_EQ(bridge.axes[j].jerk, vmc.axes[j].jerk);
  }
  EXPECT_EQ(bridge.interpolation_cycle, vmc.interpolation_cycle);
  EXPECT_TRUE(bridge.axes[0].within(0, 0) && bridge.axes[0].within(1000, 0) && bridge.axes[1].within(0, 0) && bridge.axes[1].within(1000, 0));
  const Machine m = load_machine("ucp710_like");
  EXPECT_EQ(m.chain, KinematicChain::TableTable);
  EXPECT_EQ(m.rotary_letters(), "AC");
  EXPECT_NEAR(m.axes[m.joint_of('C')].velocity, 20 * 2 * std::numbers::pi / 60, 1e-12);  // 20 rev/min
  EXPECT_TRUE(m.axes[m.joint_of('C')].continuous);
  EXPECT_NEAR(m.axes[m.joint_of('A')].min, -100 * std::numbers::pi / 180, 1e-15);
  const Machine g = load_machine("gantry_head_ac", {"setup.tool_length=80"});
  EXPECT_EQ(g.tool_length, 80);
  EXPECT_EQ(g.chain, KinematicChain::HeadHead);
  EXPECT_EQ(load_machine(DROM_SOURCE_DIR "/cases/machines/vmc_3axis.toml").chain, KinematicChain::ThreeAxis);
}

TEST(MachineFile, AValidFileParses) { EXPECT_EQ(message_of(kValid), ""); }

TEST(MachineFile, BadInputNamesTheFileLineAndKey) {
  EXPECT_NE(message_of(std::string(kValid) + "spindle_power = 15\n").find("spindle_power"), std::string::npos);
  const std::string unknown = message_of(std::string(kValid) + "[axes.X]\nveloctiy = 3\n");
  EXPECT_NE(unknown.find("m.toml"), std::string::npos) << unknown;
  EXPECT_NE(message_of(kValid, {"axes.X.velocity=-5"}).find("axes.X.velocity"), std::string::npos);
  EXPECT_NE(message_of(kValid, {"axes.X.stroke=[5, 1]"}).find("min < max"), std::string::npos);
  EXPECT_NE(message_of(kValid, {"kinematics=head_head"}).find("on the table"), std::string::npos);
  EXPECT_NE(message_of(kValid, {"axes.C.direction=[1, 0, 0]"}).find("parallel"), std::string::npos);
  EXPECT_NE(message_of(kValid, {"rotary_axes=['A', 'D']"}).find("A, B or C"), std::string::npos);
  EXPECT_NE(message_of(kValid, {"control.interpolation_cycle=0"}).find("control.interpolation_cycle"), std::string::npos);
  EXPECT_NE(message_of(kValid, {"axes.C.stroke=[0, 360]"}).find("continuous"), std::string::npos);
  const std::string line = message_of("name = \"t\"\nkinematics = \"five_axis\"\n");
  EXPECT_NE(line.find("m.toml:2"), std::string::npos) << line;
  EXPECT_NE(line.find("kinematics"), std::string::npos) << line;
  try {
    load_machine("no_such_machine");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("ucp710_like"), std::string::npos);
  }
}
