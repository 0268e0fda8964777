// Harness: a machine file (machine/machine_definition.hpp, through support/toml_reader.hpp), then its
// kinematics solving one pose (machine/kinematics.hpp). Seeds: cases/machines/*.toml.
#include "fuzz/fuzz_input.hpp"
#include "machine/kinematics.hpp"
#include "machine/machine_definition.hpp"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string origin = "fuzz_machine.toml";
  drom::fuzz::expect_clean(
      [&] {
        const auto machine = drom::machine::parse_machine(drom::fuzz::as_text(data, size), origin);
        drom::fuzz::require(machine.joint_count() >= 3 && machine.joint_count() <= drom::machine::kMaxJoints, "a machine with an impossible number of joints");
        drom::fuzz::require(std::isfinite(machine.tool_length) && machine.part_origin.allFinite(), "a machine with a non-finite set-up");
        const drom::machine::Kinematics kinematics(machine);
        drom::machine::ClPose pose;
        pose.tip = Eigen::Vector3d(10, 20, 30);
        pose.axis = Eigen::Vector3d(0.1, 0.2, 1).normalized();
        const auto branches = kinematics.inverse(pose);
        for (int b = 0; b < branches.count; ++b)
          drom::fuzz::require(branches.joints[static_cast<std::size_t>(b)].allFinite(), "a reachable pose with non-finite joints");
      },
      origin);
  return 0;
}
