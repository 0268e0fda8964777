// The post-processor's programs read back by LinuxCNC's interpreter (and by drom's fast reader) to
// the very moves it wrote, on every shipped machine; unreachable CL data refused with its line.
#include "machine/post_processor.hpp"
#include "machine/program_reader.hpp"
#include "shop_safe_program.hpp"
#include "support/input_error.hpp"

#include <gtest/gtest-spi.h>
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

using namespace drom;
using namespace drom::machine;

namespace {

ClProgram random_cl(const Machine& m, unsigned seed, int points) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(0, 1);
  ClProgram cl;
  cl.origin = "random.cl";
  Eigen::Vector3d tip = m.chain == KinematicChain::HeadHead ? Eigen::Vector3d(3000, 1500, 20) : Eigen::Vector3d(0, 0, 20);
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  for (int i = 0; i < points; ++i) {
    tip += (0.1 + 10 * u(rng)) * Eigen::Vector3d(u(rng) - 0.5, u(rng) - 0.5, 0.2 * (u(rng) - 0.5)).normalized();
    tip.z() = std::clamp(tip.z(), 0.0, 40.0);
    if (m.rotary_count() > 0) {
      axis = (axis + 0.1 * Eigen::Vector3d(u(rng) - 0.5, u(rng) - 0.5, 0)).normalized();
      if (axis.z() < std::cos(40 * std::numbers::pi / 180)) axis = (axis + Eigen::Vector3d(0, 0, 0.3)).normalized();
    }
    ClPoint p;
    p.pose = {tip, axis};
    p.feed = 200 + 5000 * u(rng);
    p.rapid = i == 0 || u(rng) < 0.05;
    p.line = i + 2;
    cl.points.push_back(p);
  }
  return cl;
}

}  // namespace

class PostProcessor : public ::testing::TestWithParam<std::string> {};

TEST_P(PostProcessor, LinuxCncReadsBackTheMovesWritten) {
  if (!rs274_available()) GTEST_SKIP() << "rs274 (linuxcnc-uspace) is not installed";
  const Machine m = load_machine(GetParam());
  const Kinematics kin(m);
  const ClProgram cl = random_cl(m, 42, 400);
  const ClOnMachine on = cl_to_machine_program(cl, kin);
  ASSERT_TRUE(on.joints.violations.empty());
  const std::string gcode = post_process(cl, kin, {.title = "round trip", .tool = 1, .spindle_speed = 12000});
  // Issue 44: ready to run as it is (tests/machine/shop_safe_program.hpp).
  shop_safe::expect_shop_safe(gcode, m.name + ".ngc");
  for (ReaderChoice reader : {ReaderChoice::Rs274, ReaderChoice::Plain}) {
    const MachineProgram back = to_machine_program(parse_program(gcode, m.name + ".ngc", {reader, {}}), m);
    // The cuts come back one for one, each from where the CL data starts it; the rapids between them
    // are the safe moves (up, across, down), so only where they end is compared.
    std::vector<const MachineBlock*> written, read;
    for (const MachineBlock& b : on.program.blocks)
      if (b.type != MoveType::Rapid) written.push_back(&b);
    for (const MachineBlock& b : back.blocks)
      if (b.type != MoveType::Rapid) read.push_back(&b);
    ASSERT_EQ(read.size(), written.size());
    for (std::size_t i = 0; i < written.size(); ++i) {
      const MachineBlock &a = *written[i], &b = *read[i];
      EXPECT_EQ(static_cast<int>(a.type), static_cast<int>(b.type)) << i;
      for (int j = 0; j < m.joint_count(); ++j) {
        EXPECT_NEAR(joint_in_program_units(m, j, a.end[j]), joint_in_program_units(m, j, b.end[j]), 1e-4) << GetParam() << " cut " << i << " joint " << j;
        EXPECT_NEAR(joint_in_program_units(m, j, a.start[j]), joint_in_program_units(m, j, b.start[j]), 1e-4) << GetParam() << " cut " << i << " joint " << j;
      }
      if (a.type == MoveType::Linear) {
        // 3-axis feeds are per length, and the length read back carries the coordinates' 4 decimals.
        const double length = (a.end.head<3>() - a.start.head<3>()).norm();
        const double relative = m.rotary_count() > 0 ? 1e-5 : 2e-4 / std::max(length, 1e-3) + 1e-5;
        EXPECT_NEAR(a.programmed_duration, b.programmed_duration, relative * a.programmed_duration) << GetParam() << " cut " << i;
      }
    }
  }
}

// The checker above fails the programs drom posted before issue 44: no spindle, a first rapid in X, Y
// and Z together down over the part, rotary axes turned low, no M5.
TEST(ShopSafeCheck, RefusesTheProgramsPostedBeforeIssue44) {
  const std::string before =
      "%\n(old)\nG21 G90 G17 G40 G94 G64 P0.0100\nT1 M6\nG43 H1\nG0 X0.0000 Y0.0000 Z2.7700 A0.0000 C0.0000\nG93 G1 X10.0000 Y0.0000 Z2.0000 A0.0000 C0.0000 F60\n"
      "G94 G0 X10.0000 Y0.0000 Z7.0000 A10.0000 C5.0000\nG0 X50.0000 Y0.0000 Z2.2000\nG93 G1 X60.0000 Y0.0000 Z2.5000 A10.0000 C5.0000 F60\nG94\nM30\n%\n";
  ::testing::TestPartResultArray failures;
  {
    ::testing::ScopedFakeTestPartResultReporter reporter(::testing::ScopedFakeTestPartResultReporter::INTERCEPT_ONLY_CURRENT_THREAD, &failures);
    shop_safe::expect_shop_safe(before, "old.ngc");
  }
  std::string all;
  for (int i = 0; i < failures.size(); ++i) all += std::string(failures.GetTestPartResult(i).message()) + "\n";
  for (const char* expected : {"G54", "the first move is not a retract in Z alone", "cuts before the spindle starts", "a rotary axis turns off the safe height",
                               "a rapid in X/Y at Z 2.2", "below the highest cut 2.5", "no M5 after the cuts"})
    EXPECT_NE(all.find(expected), std::string::npos) << expected << " not found in:\n" << all;
}

INSTANTIATE_TEST_SUITE_P(Machines, PostProcessor, ::testing::Values("vmc_3axis", "ucp710_like", "gantry_head_ac"));

TEST(PostProcessorErrors, UnreachableCutterLocationsNameTheirLine) {
  const Kinematics ucp(load_machine("ucp710_like"));
  ClProgram cl;
  cl.origin = "part.cl";
  cl.points.push_back({{{0, 0, 10}, {0, 0, 1}}, 0, true, 3});
  const double tilt = 130 * std::numbers::pi / 180;  // beyond A's [-100, 120]
  cl.points.push_back({{{5, 0, 10}, {0, std::sin(tilt), std::cos(tilt)}}, 1000, false, 4});
  try {
    post_process(cl, ucp);
    FAIL();
  } catch (const InputError& e) {
    const std::string m = e.what();
    EXPECT_NE(m.find("part.cl:4"), std::string::npos) << m;
    EXPECT_NE(m.find("A = "), std::string::npos) << m;
    EXPECT_NE(m.find("stroke"), std::string::npos) << m;
  }
  const Kinematics vmc(load_machine("vmc_3axis"));
  cl.points[1].pose.axis = Eigen::Vector3d(0, 0.2, 1).normalized();
  try {
    post_process(cl, vmc);
    FAIL();
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("cannot be reached"), std::string::npos) << e.what();
  }
}

TEST(ClFiles, AptAndCsvReadTheSamePoints) {
  const char* apt = R"(PARTNO/TEST
UNITS/MM
MULTAX/ON
$$ a comment
RAPID
GOTO/0.000,0.000,10.000,0.0,0.0,1.0
FEDRAT/1200.0,MMPM
GOTO/10.000,0.000,10.000,$
0.0,0.0,1.0
GOTO/10.000,5.000,9.000
FINI
)";
  const ClProgram a = parse_apt_cl(apt, "t.apt");
  ASSERT_EQ(a.points.size(), 3u);
  EXPECT_TRUE(a.points[0].rapid);
  EXPECT_FALSE(a.points[1].rapid);
  EXPECT_EQ(a.points[1].line, 8);
  EXPECT_NEAR(a.points[2].feed, 1200, 1e-12);
  const ClProgram b = parse_cl_csv(cl_csv(a), "t.csv");
  ASSERT_EQ(b.points.size(), 3u);
  for (std::size_t i = 0; i < 3; ++i) EXPECT_LE((a.points[i].pose.tip - b.points[i].pose.tip).norm(), 1e-6);
  auto message = [](const std::string& text) {
    try {
      parse_apt_cl(text, "bad.apt");
    } catch (const InputError& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  EXPECT_NE(message("GOTO/0,0,0\nGOTO/1,0,0\n").find("bad.apt:2"), std::string::npos);            // cutting before FEDRAT
  EXPECT_NE(message("GOTO/0,0,0\nFEDRAT/100\nGOTO/1,0,nan\n").find("bad.apt:3"), std::string::npos);  // NaN
  EXPECT_NE(message("GOTO/0,0,0,0,0,0\n").find("zero"), std::string::npos);
  EXPECT_NE(message("CYCLE/DRILL,5\n").find("CYCLE"), std::string::npos);
  EXPECT_NE(message("GOTO/0,0,$\n").find("continued"), std::string::npos);
  EXPECT_NE(message("GOTO/1e300,0,0\n").find("bad.apt:1: x: 1e300 is beyond any machine (|value| <= 1e6)"), std::string::npos);
}

// Fuzz finding (docs/robustness.md, finding 13): a header naming a column twice, then a short row,
// made the reader index past the row (ASan: SEGV in strtod).
TEST(ClFiles, ATableHeaderNamingAColumnTwiceIsRefused) {
  try {
    parse_cl_csv("x,y,z,x,i,j,k,feed\n0,0,0\n", "bad.csv");
    FAIL();
  } catch (const InputError& e) {
    EXPECT_STREQ(e.what(), "bad.csv:1: the CL table's header names column 'x' twice");
  }
}

TEST(PostProcessorErrors, ARepeatedCutterLocationIsDroppedNotRefused) {
  // A finishing path can repeat a point (a pass's last contact where the next link starts): a G1 to
  // where the tool already is has no feed, so it gets no block at all, on 3 and 5 axes alike.
  for (const char* name : {"vmc_3axis", "ucp710_like"}) {
    const Kinematics kin(load_machine(name));
    ClProgram cl;
    cl.origin = "repeat.cl";
    cl.points.push_back({{{0, 0, 10}, {0, 0, 1}}, 0, true, 2});
    cl.points.push_back({{{10, 0, 10}, {0, 0, 1}}, 1000, false, 3});
    cl.points.push_back({{{10, 0, 10}, {0, 0, 1}}, 1000, false, 4});
    cl.points.push_back({{{20, 0, 10}, {0, 0, 1}}, 1000, false, 5});
    const ClOnMachine on = cl_to_machine_program(cl, kin);
    ASSERT_EQ(on.program.blocks.size(), 2u) << name << ": the moves to x = 10 and x = 20, not the one in place";
    for (const MachineBlock& b : on.program.blocks) {
      EXPECT_EQ(static_cast<int>(b.type), static_cast<int>(MoveType::Linear)) << name;
      EXPECT_GT(b.programmed_duration, 0) << name;
    }
    const std::string gcode = post_process(cl, kin, {"repeat", 1, 12000, -1});
    EXPECT_NE(gcode.find("G1"), std::string::npos) << name;
  }
}

// A title with parentheses or a line break (a part named "bracket (rev B)") stays one comment, and a
// comment line before the opening '%' is refused as LinuxCNC refuses it.
TEST(PostProcessorText, TitlesStayCommentsAndPercentOpensTheFile) {
  const Kinematics vmc(load_machine("vmc_3axis"));
  ClProgram cl;
  cl.origin = "part.cl";
  cl.points.push_back({{{0, 0, 10}, {0, 0, 1}}, 0, true, 1});
  cl.points.push_back({{{20, 0, 2}, {0, 0, 1}}, 600, false, 2});
  const std::string gcode = post_process(cl, vmc, {.title = "bracket (rev B)\nM2"});
  EXPECT_NE(gcode.find("(bracket [rev B] M2)"), std::string::npos) << gcode;
  shop_safe::expect_shop_safe(gcode, "titled.ngc");
  try {
    parse_program("(title)\n%\nG21 G90\nG0 X0 Y0 Z5\n%\n", "late.ngc", {ReaderChoice::Plain, {}});
    ADD_FAILURE() << "a comment before the opening '%' was read";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("late.ngc:2: '%' stands only on a program's first line"), std::string::npos) << e.what();
  }
}
