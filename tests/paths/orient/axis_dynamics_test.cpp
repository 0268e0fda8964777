// Seed 000's integrator validation (Annex A1) and the forced response of a row of obstacles (§3-2.2):
// checks 1 and 2 of issue 24.
#include "paths/orient/axis_dynamics.hpp"
#include "paths/orient/tool_skin.hpp"

#include <Eigen/Geometry>
#include <gtest/gtest.h>

#include <cmath>
#include <complex>
#include <numbers>

namespace drom::paths {
namespace {

// A torus pivoted about its corner circle's centre would dip (R − r) sin α into the surface; placed by
// reference_point it touches the plane z = 0 at the contact (0, 0, 0), whatever the tilt's size and
// direction: the deepest plane point inside the cutter is at depth 0, and the contact is on the cutter.
TEST(AxisDynamics, ATiltedTorusKeepsItsContactPoint) {
  ToolAssembly tool;
  tool.cutter = {ToolKind::torus, 5, 2};
  const double offset = tool.cutter.radius - tool.cutter.corner_radius;
  FramedPath::Frame frame;
  frame.cl = Eigen::Vector3d(0, 0, tool.cutter.pivot_height());  // the tube's centre over the contact
  frame.f = Eigen::Vector3d::UnitX();
  frame.n = Eigen::Vector3d::UnitZ();
  frame.t = frame.f.cross(frame.n);
  for (double roll : {-0.5, -0.1, 0.05, 0.3})
    for (double pitch : {-0.2, 0.0, 0.17, 0.6}) {
      if (std::hypot(roll, pitch) < 0.03) continue;  // within 1° the reference slides (documented)
      const Eigen::Matrix3d R = tool_rotation(frame, roll, pitch);
      const Eigen::Vector3d reference = reference_point(frame, R.col(2), offset);
      double deepest = 0, at_contact = 1e9, deepest_fixed = 0;
      for (int i = -60; i <= 60; ++i)
        for (int j = -60; j <= 60; ++j) {
          const Eigen::Vector3d p(0.1 * i, 0.1 * j, 0);
          const double d = cutter_signed_distance(tool, R.transpose() * (p - reference));
          deepest = std::min(deepest, d);
          if (i == 0 && j == 0) at_contact = d;
          // The seed's fixed pivot, for contrast.
          deepest_fixed = std::min(deepest_fixed, cutter_signed_distance(tool, R.transpose() * (p - frame.cl)));
        }
      EXPECT_GT(deepest, -1e-9) << "roll " << roll << " pitch " << pitch;
      EXPECT_NEAR(at_contact, 0, 1e-9) << "roll " << roll << " pitch " << pitch;
      const double tilt = std::acos(R.col(2).z());
      // A fixed pivot dips its corner (R − r) sin(tilt) below the plane; a plane point's depth (its
      // distance to the cutter's boundary) is that dip where small, less where the boundary is nearer sideways.
      EXPECT_LT(deepest_fixed, -0.9 * offset * std::sin(tilt)) << "roll " << roll << " pitch " << pitch;
      EXPECT_GT(deepest_fixed, -offset * std::sin(tilt) - 0.01) << "roll " << roll << " pitch " << pitch;
    }
}

// Annex A1, Table 4.3: y' = -2xy, y(0) = 1, step 0.1, against e^{-x^2}.
TEST(AxisIntegrators, Rk4MatchesAnnexA1) {
  const OdeRhs f = [](double x, const Eigen::VectorXd& y, Eigen::VectorXd& dy) { dy = -2 * x * y; };
  const std::vector<double> xs{0.1, 0.2, 0.3, 0.4, 0.5, 1.0, 2.0, 3.0};
  const auto rk4 = integrate_rk4(f, 0, Eigen::VectorXd::Ones(1), xs, 0.1);
  const double table[] = {0.9900, 0.9608, 0.9139, 0.8521, 0.7788};
  for (std::size_t i = 0; i < 5; ++i) EXPECT_NEAR(rk4[i](0), table[i], 5e-5) << "x = " << xs[i];
  for (std::size_t i = 0; i < xs.size(); ++i) EXPECT_NEAR(rk4[i](0), std::exp(-xs[i] * xs[i]), 2e-5) << "x = " << xs[i];
  const auto ark = integrate_arkode(f, 0, Eigen::VectorXd::Ones(1), xs, 1e-10, 1e-12);
  for (std::size_t i = 0; i < xs.size(); ++i) EXPECT_NEAR(ark[i](0), std::exp(-xs[i] * xs[i]), 1e-8) << "x = " << xs[i];
}

// Annex A1: y'' + 2 alpha y' + w0^2 y = 0, alpha = 1, y(0) = 1, y'(0) = 0, dt = 0.1, in its three
// regimes (w0^2 = 50, 1, 0.4), against the closed form (at xi = 1 the form the seed's formula misses).
TEST(AxisIntegrators, DampedOscillatorThreeRegimes) {
  for (double w2 : {50.0, 1.0, 0.4}) {
    const double w0 = std::sqrt(w2), xi = 1 / w0;
    const OdeRhs f = [&](double, const Eigen::VectorXd& y, Eigen::VectorXd& dy) {
      dy.resize(2);
      dy << y(1), -2 * y(1) - w2 * y(0);
    };
    std::vector<double> ts;
    for (int i = 1; i <= 50; ++i) ts.push_back(0.1 * i);
    const auto rk4 = integrate_rk4(f, 0, Eigen::Vector2d(1, 0), ts, 0.1);
    const auto ark = integrate_arkode(f, 0, Eigen::Vector2d(1, 0), ts, 1e-10, 1e-12);
    double worst_rk4 = 0, worst_ark = 0;
    for (std::size_t i = 0; i < ts.size(); ++i) {
      const double exact = free_response(1, 0, w0, xi, ts[i]);
      worst_rk4 = std::max(worst_rk4, std::abs(rk4[i](0) - exact));
      worst_ark = std::max(worst_ark, std::abs(ark[i](0) - exact));
    }
    EXPECT_LT(worst_rk4, w2 > 10 ? 1e-2 : 1e-5) << "w0^2 = " << w2;  // w0 dt = 0.71 at w0^2 = 50
    std::cout << "w0^2 = " << w2 << ": RK4 max error " << worst_rk4 << ", ARKODE " << worst_ark << "\n";
    EXPECT_LT(worst_ark, 1e-7) << "w0^2 = " << w2;
  }
  // The critical form is the limit of the other two.
  EXPECT_NEAR(free_response(1, 0.3, 5, 1, 0.7), free_response(1, 0.3, 5, 1 + 1e-7, 0.7), 1e-6);
  EXPECT_NEAR(free_response(1, 0.3, 5, 1, 0.7), free_response(1, 0.3, 5, 1 - 1e-7, 0.7), 1e-6);
}

TEST(AxisIntegrators, RecallFromTheSeedsTable31) {
  RecallParameters r;  // k = 1 N m/rad, v0 = 1 m/min, d0 = 2 mm
  EXPECT_NEAR(r.omega0(), 52.36, 0.01);
  EXPECT_NEAR(r.inertia() * 1e-3, 3.65e-4, 0.01e-4);   // kg m^2 (N mm s^2 -> N m s^2)
  EXPECT_NEAR(r.damping() * 1e-3, 38.20e-3, 0.02e-3);
}

// The fundamental's amplitude of x over whole periods of `period` (mm of s) between a and b.
double fundamental(const std::vector<double>& s, const std::vector<double>& x, double period, double a, double b) {
  std::complex<double> sum = 0;
  double mean = 0;
  int n = 0;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (s[i] >= a && s[i] < b) {
      mean += x[i];
      ++n;
    }
  mean /= n;
  for (std::size_t i = 0; i < s.size(); ++i)
    if (s[i] >= a && s[i] < b) sum += (x[i] - mean) * std::exp(std::complex<double>(0, -2 * std::numbers::pi * s[i] / period));
  return 2 * std::abs(sum) / n;
}

// §3-2.2: a row of obstacles spaced d forces the pendulum at w = 2 pi v0 / d; at xi = 1 the ripple of
// theta against the ripple of M/k is 1 / (1 + rho^2), rho = w / w0 = d0 / d (-14 dB at rho = 2).
TEST(AxisDynamics, RowOfObstaclesIsLowPassFiltered) {
  for (double rho : {0.5, 1.0, 2.0}) {
    const double d0 = 8, d = d0 / rho, lever = 20;
    std::vector<Eigen::Vector3d> points, normals;
    for (double x = -40; x <= 240; x += d) {
      points.emplace_back(x, -3, lever);  // beside G, which travels along x at height `lever`
      normals.emplace_back(0, 1, 0);
    }
    const KhatibParameters k{100, 10};
    const ObstacleCloud row(points, normals, k.influence_radius);
    const DirectField field(row, k, Aggregation::F1);
    const FramedPath path = FramedPath::from_points({{-20, 0, 0}, {220, 0, 0}}, {{0, 0, 1}, {0, 0, 1}}, 0, 0);
    DynamicsSettings st;
    st.recall.spacing = d0;
    st.recall.stiffness = 20000;  // small tilts: G stays close to its line
    st.moment = MomentModel::PointG;
    st.lever_g = lever;
    st.output_step = d / 64;
    st.relative_tolerance = 1e-9;
    st.absolute_tolerance = 1e-11;
    const AxisHistory h = integrate_axis(path, {}, field, st);
    std::vector<double> s, theta, forcing;
    const FramedPath::Frame fr = path.at(0);
    for (const auto& a : h.samples) {
      s.push_back(a.s);
      theta.push_back(a.roll);
      forcing.push_back(a.moment.dot(fr.f) / st.recall.stiffness);
    }
    // Steady state: from 4 d0 after the row's start (transient e^{-w0 t}), whole periods, away from the ends.
    const double a = 80, b = a + std::floor(100 / d) * d;
    const double ratio = fundamental(s, theta, d, a, b) / fundamental(s, forcing, d, a, b);
    const double expected = 1 / (1 + rho * rho);
    std::cout << "rho = " << rho << ": amplitude ratio " << ratio << " vs 1/(1+rho^2) = " << expected << "\n";
    EXPECT_NEAR(ratio / expected, 1, 0.10) << "rho = " << rho << ": ratio " << ratio << ", 1/(1+rho^2) = " << expected
                                           << " (" << 20 * std::log10(ratio) << " dB)";
  }
}

}  // namespace
}  // namespace drom::paths
