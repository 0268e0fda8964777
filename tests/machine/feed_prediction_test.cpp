// The feed a program really reaches: closed forms on long straight blocks, the seed's saddle oracle
// near the table-table singularity, and every limit respected on random programs.
#include "machine/cl_data.hpp"
#include "machine/feed_prediction.hpp"
#include "machine/gcode_reader.hpp"
#include "machine/scurve.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>

using namespace drom::machine;

namespace {

constexpr double kPi = std::numbers::pi;

FeedPrediction predict(const std::string& gcode, const Machine& m) {
  const Kinematics kin(m);
  return predict_feed(to_machine_program(parse_plain_gcode(gcode, "test.ngc"), m), kin);
}

// A pass along x over the saddle z = (x² - y²) / (2c) at y = y0, the tool tilted by `tilt` across the
// feed (yaw 90°): the tool axis's horizontal part passes within sin(tilt) of zero at x = 0, where C
// must turn fastest (../shared/reference/003-digest.md §3.3).
ClProgram saddle_pass(double c, double tilt, double y0, double step, double feed) {
  ClProgram cl;
  for (double x = -40; x <= 40 + 1e-9; x += step) {
    const Eigen::Vector3d n = Eigen::Vector3d(-x / c, y0 / c, 1).normalized();
    const Eigen::Vector3d f = Eigen::Vector3d(1, 0, x / c).normalized();
    const Eigen::Vector3d b = n.cross(f).normalized();
    ClPoint p;
    p.pose.tip = {x, y0, (x * x - y0 * y0) / (2 * c)};
    p.pose.axis = (std::cos(tilt) * n + std::sin(tilt) * b).normalized();
    p.feed = feed;
    p.rapid = cl.points.empty();
    cl.points.push_back(p);
  }
  return cl;
}

double rest_to_rest_time_for_test(double length, const MotionLimits& limits) { return plan_double_s(0, 0, length, limits).duration(); }

}  // namespace

TEST(FeedPrediction, LongStraightBlocksRunAtTheProgrammedFeedAndSumTheClosedForms) {
  const Machine m = load_machine("vmc_3axis");
  // Exact stop (G61.1): every block is a rest-to-rest move. Blocks along X, Y, Z and one diagonal.
  const std::string program = "G21 G90 G61.1\nG0 X0 Y0 Z5\nG1 Z0 F3000\nX100\nY10\nX0\nY20\nX100 Y50\nG0 Z5\nM30\n";
  const FeedPrediction p = predict(program, m);
  const double F = 3000.0 / 60;
  double expected = 0, expected_at_feed = 0;
  const std::vector<Eigen::Vector3d> moves{{0, 0, -5}, {100, 0, 0}, {0, 10, 0}, {-100, 0, 0}, {0, 10, 0}, {100, 30, 0}};
  for (const Eigen::Vector3d& d : moves) {
    const double L = d.norm();
    double A = 1e300, J = 1e300;
    for (int k = 0; k < 3; ++k)
      if (std::abs(d[k]) > 0) A = std::min(A, m.axes[k].acceleration * L / std::abs(d[k])), J = std::min(J, m.axes[k].jerk * L / std::abs(d[k]));
    // Which closed form applies: V reached here in every block (checked), A reached or not.
    const double ramp = speed_change_distance(0, F, A, J);
    ASSERT_LT(2 * ramp, L);
    const double t = F * J >= A * A ? L / F + A / J + F / A : L / F + 2 * std::sqrt(F / J);
    expected += t;
    expected_at_feed += L - 2 * ramp;
  }
  // The last rapid runs at the axes' own limits (Z: V 500, A 5000, J 50000, 5 mm).
  const double rapid = rest_to_rest_time_for_test(5, {m.axes[2].velocity, m.axes[2].acceleration, m.axes[2].jerk});
  EXPECT_NEAR(p.cycle_time, expected + rapid, 1e-9 * p.cycle_time);
  EXPECT_NEAR(p.length_at_programmed_feed, expected_at_feed, 1e-6);
  EXPECT_NEAR(p.cutting_length, 5 + 100 + 10 + 100 + 10 + std::hypot(100, 30), 1e-9);
  for (const BlockPrediction& b : p.blocks)
    if (b.length > 0 && b.programmed_duration > 0) {
      EXPECT_EQ(b.cap_source, FeedLimit::ProgrammedFeed);
      EXPECT_NEAR(b.max_speed, F, 1e-9 * F);
    }
  // Blending the corners (G64, the machine's 0.01 mm) is faster, but not faster than the feed allows.
  std::string blended = program;
  blended.replace(blended.find("G61.1"), 5, "G64");
  const FeedPrediction q = predict(blended, m);
  EXPECT_LT(q.cycle_time, p.cycle_time);
  EXPECT_GT(q.cycle_time, (5 + 100 + 10 + 100 + 10 + std::hypot(100, 30)) / F);
}

TEST(FeedPrediction, SaddleOracleTheCLimitedFeedRisesFiveFoldFromOneToFiveDegrees) {
  // ../shared/reference/003-digest.md §3.3: c = 100 mm, C limited to 20 rev/min on the table-table
  // machine; the C-limited feed at the crossing is Ċ_max c tan θ: 219 mm/min at 1°, 1099 at 5°
  // (the digest's sin θ form gives 219 and 1096). CL points every 0.1 mm, programmed at 3000 mm/min.
  //   - As shipped (G642 blending, 0.01° rotary tolerance, 4 ms cycle): the C-limited feed is the
  //     oracle's; the tool goes slower still at 1°, where C's polyline has corners beyond the tolerance.
  //   - With a control that joins the corners (smooth, 0.05°, 1 ms): the tool runs at the C-limited feed.
  const std::array<double, 2> tilts{1 * kPi / 180, 5 * kPi / 180};
  const std::vector<std::vector<std::string>> settings{
      {}, {"control.junction=smooth", "control.junction_tolerance_rotary=0.05", "control.interpolation_cycle=0.001"}};
  for (std::size_t setting = 0; setting < settings.size(); ++setting) {
    const Machine m = load_machine("ucp710_like", settings[setting]);
    const Kinematics kin(m);
    const int c_axis = m.joint_of('C');
    std::array<double, 2> c_limited{}, slowest{};
    for (int k = 0; k < 2; ++k) {
      const ClOnMachine on = cl_to_machine_program(saddle_pass(100, tilts[k], 0, 0.1, 3000), kin);
      ASSERT_TRUE(on.joints.violations.empty());
      const FeedPrediction p = predict_feed(on.program, kin);
      double lowest_cap = 1e300;
      int lowest_cap_axis = -1;
      for (const BlockPrediction& b : p.blocks)
        if (b.path_limit[0] < lowest_cap) lowest_cap = b.path_limit[0], lowest_cap_axis = b.limiting_axis[0];
      EXPECT_EQ(lowest_cap_axis, c_axis);
      c_limited[k] = lowest_cap * 60;
      // Away from the pass's ends (its ramps), the slowest the tool goes: at the crossing.
      slowest[k] = 1e300;
      for (const BlockPrediction& b : p.blocks)
        if (b.s_start > 10 && b.s_start < p.blocks.back().s_start - 10) slowest[k] = std::min(slowest[k], b.min_speed * 60);
      const double oracle = m.axes[c_axis].velocity * 100 * std::tan(tilts[k]) * 60;
      EXPECT_NEAR(c_limited[k], oracle, 0.1 * oracle) << "tilt " << k;
      EXPECT_LE(slowest[k], c_limited[k] * (1 + 1e-9));
      const std::string tag = (setting == 0 ? "shipped" : "smooth") + std::string(k == 0 ? "_1deg" : "_5deg");
      RecordProperty("c_limited_feed_" + tag, std::to_string(c_limited[k]));
      RecordProperty("slowest_feed_" + tag, std::to_string(slowest[k]));
    }
    EXPECT_NEAR(c_limited[0], 219, 0.1 * 219);
    EXPECT_NEAR(c_limited[1], 1096, 0.1 * 1096);
    EXPECT_NEAR(c_limited[1] / c_limited[0], 5.0, 0.5);
    if (setting == 1) {
      EXPECT_NEAR(slowest[0], c_limited[0], 0.1 * c_limited[0]);
      EXPECT_NEAR(slowest[1], c_limited[1], 0.1 * c_limited[1]);
      EXPECT_NEAR(slowest[1] / slowest[0], 5.0, 0.5);
    }
  }
}

TEST(FeedPrediction, RandomProgramsRespectEveryLimit) {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(0, 1);
  for (const char* name : {"vmc_3axis", "ucp710_like", "gantry_head_ac"}) {
    const Machine m = load_machine(name);
    const Kinematics kin(m);
    for (int trial = 0; trial < 6; ++trial) {
      // A random walk of CL points: short and long segments, varying feeds, tool axes within 40° of z.
      ClProgram cl;
      Eigen::Vector3d tip = m.chain == KinematicChain::HeadHead ? Eigen::Vector3d(3000, 1500, 20) : Eigen::Vector3d(0, 0, 20);
      Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
      for (int i = 0; i < 300; ++i) {
        const double len = u(rng) < 0.3 ? 0.05 + 0.2 * u(rng) : 1 + 20 * u(rng);
        tip += len * Eigen::Vector3d(u(rng) - 0.5, u(rng) - 0.5, 0.2 * (u(rng) - 0.5)).normalized();
        tip.z() = std::clamp(tip.z(), 0.0, 40.0);
        if (m.rotary_count() > 0) {
          axis = (axis + 0.15 * Eigen::Vector3d(u(rng) - 0.5, u(rng) - 0.5, 0)).normalized();
          if (axis.z() < std::cos(40 * kPi / 180)) axis = (axis + Eigen::Vector3d(0, 0, 0.3)).normalized();
        }
        ClPoint p;
        p.pose = {tip, axis};
        p.feed = 500 + 6000 * u(rng);
        p.rapid = i == 0 || u(rng) < 0.05;
        cl.points.push_back(p);
      }
      const ClOnMachine on = cl_to_machine_program(cl, kin);
      const FeedPrediction p = predict_feed(on.program, kin);
      double t_sum = 0;
      for (const BlockPrediction& b : p.blocks) {
        t_sum += b.duration;
        EXPECT_LE(b.max_speed, b.cap * (1 + 1e-9)) << name;
        EXPECT_GE(b.duration, 0);
      }
      EXPECT_NEAR(t_sum, p.cycle_time, 1e-9 * p.cycle_time);
      // Sample the motion: each axis within its velocity, the path within its acceleration and jerk.
      const int samples = 20000;
      for (int k = 0; k <= samples; ++k) {
        const PathState st = p.at_time(p.cycle_time * k / samples);
        const BlockPrediction& b = p.blocks[st.block];
        if (!(b.length > 0)) continue;
        EXPECT_LE(st.v, b.cap * (1 + 1e-6)) << name << " block " << st.block;
        EXPECT_LE(std::abs(st.a), b.path_limit[1] * (1 + 1e-6)) << name << " block " << st.block;
        EXPECT_LE(std::abs(st.j), b.path_limit[2] * (1 + 1e-6)) << name << " block " << st.block;
        const JointState js = p.joints_at(st);
        for (int j = 0; j < m.joint_count(); ++j) EXPECT_LE(std::abs(js.velocity[j]), m.axes[j].velocity * (1 + 1e-6)) << name << " joint " << j;
      }
      // Junctions: the speed at each block end stays within its limit.
      for (std::size_t i = 0; i + 1 < p.blocks.size(); ++i) {
        const BlockPrediction& b = p.blocks[i];
        if (!(b.length > 0)) continue;
        const PathState end = p.at_time(b.t_start + b.duration);
        EXPECT_LE(end.v, b.end_speed_limit * (1 + 1e-6) + 1e-9) << name << " junction " << i;
      }
    }
  }
}

TEST(FeedPrediction, ShortBlocksAreCappedByTheInterpolationCycle) {
  Machine m = load_machine("vmc_3axis");
  std::string program = "G21 G90 G64\nG0 X0 Y0 Z0\nG1 F6000\n";
  char block[32];
  for (int i = 1; i <= 2000; ++i) {  // collinear 0.02 mm blocks
    std::snprintf(block, sizeof block, "X%.2f\n", 0.02 * i);
    program += block;
  }
  program += "M2\n";
  const FeedPrediction p = predict(program, m);
  const double cap = 0.02 / m.interpolation_cycle;  // 20 mm/s, below the programmed 100 mm/s
  for (std::size_t i = 0; i < p.blocks.size(); ++i)
    if (p.blocks[i].length > 0) {
      EXPECT_EQ(p.blocks[i].cap_source, FeedLimit::InterpolationCycle);
      EXPECT_LE(p.blocks[i].max_speed, cap * (1 + 1e-9));
    }
  // Collinear blocks do not slow down at their junctions: the tool cruises at the cycle's cap.
  EXPECT_NEAR(p.blocks[1000].min_speed, cap, 1e-9 * cap);
}
