// Inverse and forward kinematics of every shipped machine: FK∘IK is the identity, both branches are
// found, C unwinds continuously through full turns, and the singularity is detected.
#include "machine/kinematics.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>

using namespace drom::machine;

namespace {

constexpr double kPi = std::numbers::pi;

// Random joints within the strokes (continuous axes within ±π), away from the singular direction.
Joints random_joints(const Kinematics& kin, std::mt19937& rng) {
  const Machine& m = kin.machine();
  std::uniform_real_distribution<double> u(0, 1);
  for (;;) {
    Joints q = Joints::Zero();
    for (int j = 0; j < m.joint_count(); ++j) {
      const AxisLimits& a = m.axes[j];
      double lo = a.continuous ? -kPi : a.min, hi = a.continuous ? kPi : a.max;
      if (j == 2 && kin.tip_controlled()) lo -= m.tool_length, hi -= m.tool_length;  // the stroke bounds the gauge line
      q[j] = lo + (hi - lo) * u(rng);
    }
    if (kin.singularity_distance(kin.forward(q).axis) > 5 * kPi / 180 || m.rotary_count() == 0) return q;
  }
}

double angle_gap(double a, double b) { return std::abs(std::remainder(a - b, 2 * kPi)); }

}  // namespace

class ShippedMachine : public ::testing::TestWithParam<std::string> {};

TEST_P(ShippedMachine, ForwardOfInverseIsTheIdentityOnBothBranches) {
  const Kinematics kin(load_machine(GetParam()));
  const Machine& m = kin.machine();
  std::mt19937 rng(1234);
  int two_branches = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Joints q = random_joints(kin, rng);
    const ClPose pose = kin.forward(q);
    ASSERT_NEAR(pose.axis.norm(), 1, 1e-14);
    const IkBranches ik = kin.inverse(pose);
    ASSERT_GE(ik.count, 1);
    EXPECT_FALSE(ik.singular);
    bool found_original = false;
    for (int b = 0; b < ik.count; ++b) {
      const ClPose back = kin.forward(ik.joints[b]);
      const double scale = std::max(1.0, pose.tip.norm());
      EXPECT_LE((back.tip - pose.tip).norm(), 1e-12 * scale) << m.name << " branch " << b;
      EXPECT_LE((back.axis - pose.axis).norm(), 1e-12) << m.name << " branch " << b;
      bool same = (ik.joints[b].head<3>() - q.head<3>()).norm() <= 1e-12 * scale;
      for (int j = 3; j < m.joint_count(); ++j) same = same && angle_gap(ik.joints[b][j], q[j]) < 1e-12;
      found_original = found_original || same;
    }
    EXPECT_TRUE(found_original) << m.name;
    two_branches += ik.count == 2;
  }
  if (m.rotary_count() == 2) {
    EXPECT_EQ(two_branches, 20000) << "both branches, away from the singularity";
  }
}

INSTANTIATE_TEST_SUITE_P(Machines, ShippedMachine, ::testing::Values("vmc_3axis", "bridge_3axis", "ucp710_like", "gantry_head_ac"));

TEST(Kinematics, TableTableBranchesMirrorTheTiltAndTurnCByHalfATurn) {
  const Kinematics kin(load_machine("ucp710_like"));
  const double tilt = 30 * kPi / 180, azimuth = 40 * kPi / 180;
  const ClPose pose{{10, 20, 5}, {std::sin(tilt) * std::cos(azimuth), std::sin(tilt) * std::sin(azimuth), std::cos(tilt)}};
  const IkBranches ik = kin.inverse(pose);
  ASSERT_EQ(ik.count, 2);
  EXPECT_NEAR(ik.joints[0][3], -ik.joints[1][3], 1e-12);              // A and -A
  EXPECT_NEAR(angle_gap(ik.joints[0][4], ik.joints[1][4]), kPi, 1e-12);  // C and C + 180°
  EXPECT_NEAR(std::abs(ik.joints[0][3]), tilt, 1e-12);
}

TEST(Kinematics, CUnwindsContinuouslyThroughFullTurns) {
  for (const char* name : {"ucp710_like", "gantry_head_ac"}) {
    const Kinematics kin(load_machine(name));
    std::vector<ClPose> poses;
    const double tilt = 25 * kPi / 180;
    const int steps = 1080;  // one and a half turns of the tool axis about z
    const Eigen::Vector3d centre = kin.machine().chain == KinematicChain::HeadHead ? Eigen::Vector3d(3000, 1500, 10) : Eigen::Vector3d(0, 0, 10);
    for (int k = 0; k <= steps; ++k) {
      const double az = 3 * kPi * k / steps;
      poses.push_back({centre + Eigen::Vector3d(30 * std::cos(az), 30 * std::sin(az), 0), {std::sin(tilt) * std::cos(az), std::sin(tilt) * std::sin(az), std::cos(tilt)}});
    }
    const JointPath path = inverse_path(kin, poses);
    const int c = kin.machine().joint_of('C');
    ASSERT_GE(c, 0);
    if (kin.machine().axes[c].continuous) {
      EXPECT_TRUE(path.violations.empty()) << name;
      for (std::size_t k = 1; k < poses.size(); ++k) EXPECT_LT(std::abs(path.joints[k][c] - path.joints[k - 1][c]), 1.1 * 3 * kPi / steps) << name;
      EXPECT_NEAR(std::abs(path.joints.back()[c] - path.joints.front()[c]), 3 * kPi, 1e-9) << name;
    } else {
      // C limited to ±360°: 540° does not fit, so the path switches branch once (C half a turn back,
      // A mirrored) when C meets its end stop, and never leaves the stroke.
      EXPECT_TRUE(path.violations.empty()) << name << ": " << (path.violations.empty() ? "" : path.violations[0].what);
      int switches = 0;
      for (std::size_t k = 1; k < poses.size(); ++k) {
        if (std::abs(path.joints[k][c] - path.joints[k - 1][c]) < 1.1 * 3 * kPi / steps) continue;
        ++switches;
        EXPECT_NE(path.branch[k], path.branch[k - 1]);
        EXPECT_NEAR(std::abs(path.joints[k][c] - path.joints[k - 1][c]), kPi, 0.02);
      }
      EXPECT_EQ(switches, 1) << name;
    }
    for (std::size_t k = 0; k < poses.size(); ++k) {
      const ClPose back = kin.forward(path.joints[k]);
      EXPECT_LE((back.tip - poses[k].tip).norm(), 1e-9);
      EXPECT_LE((back.axis - poses[k].axis).norm(), 1e-12);
    }
  }
}

TEST(Kinematics, SingularityIsDetectedAndTheFreeAngleKeepsItsValue) {
  const Kinematics kin(load_machine("ucp710_like"));
  std::vector<ClPose> poses;
  for (int k = 0; k <= 20; ++k) {
    const double tilt = (10 - k) * kPi / 180;  // through the vertical at k = 10
    poses.push_back({{0, 0, 0}, {std::sin(tilt) * std::cos(0.3), std::sin(tilt) * std::sin(0.3), std::cos(tilt)}});
  }
  const JointPath path = inverse_path(kin, poses);
  EXPECT_NEAR(path.singularity_distance[10], 0, 1e-12);
  EXPECT_NEAR(path.singularity_distance[0], 10 * kPi / 180, 1e-12);
  const IkBranches at = kin.inverse(poses[10], 1.25);
  EXPECT_TRUE(at.singular);
  EXPECT_EQ(at.count, 1);
  EXPECT_NEAR(at.joints[0][4], 1.25, 1e-12);  // C stays where it was
  EXPECT_NEAR(path.joints[10][4], path.joints[9][4], 1e-12);
  EXPECT_TRUE(path.violations.empty());
}

TEST(Kinematics, StrokesAreCheckedAndAThreeAxisMachineOnlyReachesAVerticalTool) {
  const Kinematics vmc(load_machine("vmc_3axis"));
  EXPECT_EQ(vmc.inverse({{0, 0, 0}, {0, 0.1, 0.995}}).count, 0);
  std::vector<ClPose> poses{{{0, 0, 0}, {0, 0, 1}}, {{450, 0, 0}, {0, 0, 1}}, {{0, 0, -60}, {0, 0, 1}}};
  const JointPath path = inverse_path(vmc, poses);
  ASSERT_EQ(path.violations.size(), 2u);
  EXPECT_EQ(path.violations[0].pose, 1u);
  EXPECT_NE(path.violations[0].what.find("X = 450"), std::string::npos) << path.violations[0].what;
  EXPECT_NE(path.violations[1].what.find("gauge line"), std::string::npos) << path.violations[1].what;
  // A tilt beyond A's stroke on the table-table machine: neither branch's A fits [-100, 120].
  const Kinematics ucp(load_machine("ucp710_like"));
  const double tilt = 130 * kPi / 180;
  const std::vector<ClPose> tilted{{{0, 0, 0}, {0, std::sin(tilt), std::cos(tilt)}}};
  const JointPath t = inverse_path(ucp, tilted);
  ASSERT_FALSE(t.violations.empty());
  EXPECT_NE(t.violations[0].what.find("A = "), std::string::npos) << t.violations[0].what;
}
