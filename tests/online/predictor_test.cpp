// The online predictor on a synthetic model (tests/reduce/synthetic_model.hpp): recovery of a profile
// inside the basis, calibration of its uncertainty, dropped points, the learning phase and rate
// limit, the ball end mill's offset, and concurrent ingest and queries.
#include "online/predictor.hpp"
#include "tests/online/synthetic_profiles.hpp"
#include "tests/reduce/synthetic_model.hpp"

#include <Eigen/Cholesky>
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <thread>

using namespace drom;
using online::MeasuredPoint;
using test::profile;
using test::profile_times;
using test::tool_at;

namespace {

double no_offset(double) { return 0.0; }

}  // namespace

TEST(Predictor, RecoversAProfileInsideTheBasisAndItsFinalShape) {
  // Check 2 of the issue: noise-free readings of a profile inside the basis; the tool-length offsets
  // change during the run (the readings account for the offset in force where each point was cut).
  const reduce::LightModel m = test::synthetic_model();
  online::PredictorSettings s;
  s.prior_scale = 1e6;  // a prior that does not pull: what the data say
  s.noise_sd = 0.05;
  online::Predictor predictor(m, s);
  const Eigen::VectorXd alpha = (Eigen::VectorXd(4) << 0.8, -1.3, 0.4, 2.1).finished();
  auto offset = [](double t) { return t < 30 ? 0.0 : t < 60 ? 0.02 : -0.015; };
  predictor.record_offset(30, 0.02);  // between profiles: the controller says when
  predictor.record_offset(60, -0.015);
  std::mt19937 rng(1);
  online::ProfileReport total;
  for (double t : profile_times()) {
    const auto r = predictor.add_profile(t, {tool_at(m, t), offset(t)}, profile(m, alpha, t, 0, rng, offset));
    total.used += r.used, total.not_yet_cut += r.not_yet_cut, total.outside += r.outside;
  }
  const online::Estimate e = predictor.estimate();
  const double alpha_error = (e.alpha - alpha).cwiseAbs().maxCoeff() / alpha.cwiseAbs().maxCoeff();
  const online::FinalShape shape = predictor.final_shape();
  const Eigen::VectorXd truth = m.final_basis * alpha;
  const double shape_error = (Eigen::Map<const Eigen::VectorXd>(shape.displacement.data(), shape.displacement.size()) - truth).cwiseAbs().maxCoeff();
  std::printf("inside the basis: %d points used (%d not yet cut, %d off the surface), alpha error %.2e (relative), final shape %.2e mm\n", total.used,
              total.not_yet_cut, total.outside, alpha_error, shape_error);
  EXPECT_GT(total.used, 10000);
  EXPECT_LT(alpha_error, 1e-8);
  EXPECT_LT(shape_error, 1e-6);
  EXPECT_TRUE(e.learned);
}

TEST(Predictor, NinetyFivePercentBandCoversTheTruthAtNinetyFivePercentOfNodes) {
  // Check 4: 200 runs, each with coefficients drawn from the prior and N(0, 0.05) noise; the final
  // shape's 95 % band (1.96 sd) must cover the truth at 95 +- 3 % of the (run, node) pairs. Few
  // profiles (the first two passes) so that the band is wide and the prior matters. The prior has a
  // mean of its own (a case's expected profile), and the draws are around it.
  reduce::LightModel m = test::synthetic_model();
  m.prior_mean = (Eigen::VectorXd(4) << 0.5, -1.0, 0.3, 0.8).finished();
  std::mt19937 rng(2024);
  std::normal_distribution<double> gauss(0, 1);
  long long covered = 0, total = 0;
  double mean_sd = 0;
  std::vector<double> times;
  for (double t : profile_times())
    if (t < 45 && static_cast<int>(t) % 4 == 1) times.push_back(t);
  for (int run = 0; run < 200; ++run) {
    Eigen::VectorXd alpha(m.rank());
    for (int k = 0; k < m.rank(); ++k) alpha[k] = m.prior_mean[k] + m.prior_sd[k] * gauss(rng);
    online::Predictor predictor(m, {});
    for (double t : times) predictor.add_profile(t, {tool_at(m, t), 0.0}, profile(m, alpha, t, 0.05, rng, no_offset));
    const online::FinalShape shape = predictor.final_shape();
    const Eigen::VectorXd truth = m.final_basis * alpha;
    for (Eigen::Index n = 0; n < shape.nodes.cols(); ++n) {
      covered += std::abs(shape.displacement(2, n) - truth[3 * n + 2]) <= 1.96 * shape.sd(2, n);
      mean_sd += shape.sd(2, n);
      ++total;
    }
  }
  const double coverage = static_cast<double>(covered) / static_cast<double>(total);
  std::printf("coverage of the 95 %% band: %.2f %% of %lld (run, node) pairs; mean sd %.4f mm\n", 100 * coverage, total, mean_sd / static_cast<double>(total));
  EXPECT_NEAR(coverage, 0.95, 0.03);
}

TEST(Predictor, WithoutReadingsTheEstimateIsThePriorMean) {
  reduce::LightModel m = test::synthetic_model();
  m.prior_mean = (Eigen::VectorXd(4) << 0.5, -1.0, 0.3, 0.8).finished();
  const online::Predictor predictor(m, {});
  const online::Estimate e = predictor.estimate();
  EXPECT_LT((e.alpha - m.prior_mean).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_LT((e.covariance.diagonal().cwiseSqrt() - m.prior_sd).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(Predictor, DropsAndCountsWhatIsNotTheMachinedSurface) {
  const reduce::LightModel m = test::synthetic_model();
  online::Predictor predictor(m, {});
  const Eigen::VectorXd alpha = Eigen::VectorXd::Ones(4);
  const double t = 10;  // first pass, tool at x = 100
  const Eigen::Vector3d tool = tool_at(m, t);
  std::vector<MeasuredPoint> pts;
  pts.push_back({tool.x() - 20, 10, test::reading(m, alpha, tool.x() - 20, 10, t, no_offset)});  // good
  pts.push_back({tool.x() - 20, 12, std::nan("")});                                       // no reading
  pts.push_back({-5, 10, 8.0});                                                            // off the target surface
  pts.push_back({tool.x() + 40, 10, 10.0});                                                // ahead of the tool: not cut yet
  pts.push_back({tool.x() - 20, 60, 10.0});                                                // another pass's strip: not cut yet
  pts.push_back({tool.x() - 20, 14, 8.0 + 3.0});                                           // 3 mm off: a wall or a glitch
  const auto r = predictor.add_profile(t, {tool, 0.0}, pts);
  EXPECT_EQ(r.used, 1);
  EXPECT_EQ(r.invalid, 1);
  EXPECT_EQ(r.outside, 1);
  EXPECT_EQ(r.not_yet_cut, 2);
  EXPECT_EQ(r.out_of_range, 1);
  EXPECT_EQ(predictor.add_profile(5, {tool, 0.0}, pts).rejected, std::string("older than the last profile"));  // out of time order: left out, not an error
  EXPECT_EQ(predictor.rejections().out_of_order, 1);
}

TEST(Predictor, NoOffsetUntilLearnedThenTheEstimateRateLimited) {
  const reduce::LightModel m = test::synthetic_model();
  online::PredictorSettings s;
  s.max_offset_rate = 0.001;  // mm/s of program time
  online::Predictor predictor(m, s);
  const Eigen::VectorXd alpha = (Eigen::VectorXd(4) << 1.5, 1.0, -0.5, 0.7).finished();
  std::mt19937 rng(3);
  const auto times = profile_times();
  double learned_at = -1;
  for (double t : times) {
    predictor.add_profile(t, {tool_at(m, t), 0.0}, profile(m, alpha, t, 0.0, rng, no_offset));
    if (learned_at < 0 && predictor.estimate().learned) learned_at = t;
    if (learned_at < 0) {
      EXPECT_EQ(predictor.tool_offset(t), 0.0) << "an offset before learning, at t = " << t;
    }
  }
  ASSERT_GT(learned_at, 0);
  // After learning: the offset follows the prediction, never faster than the rate limit.
  const double t0 = times.back();
  double last = predictor.tool_offset(t0);
  for (double t = t0 + 0.5; t < t0 + 20; t += 0.5) {
    const double o = predictor.tool_offset(t);
    EXPECT_LE(std::abs(o - last), 0.001 * 0.5 + 1e-15);
    last = o;
  }
  // The unlimited prediction is the target surface's displacement under the tool.
  const double tp = 110;
  const Eigen::Vector3d tool = tool_at(m, tp);
  EXPECT_NEAR(predictor.predicted_offset(tp), predictor.target_altitude(tool.x(), tool.y(), tp) - 8.0, 1e-4);
  std::printf("learned after the profile at t = %.1f s (of %.1f)\n", learned_at, times.back());
}

TEST(Predictor, BallEndMillRidesTheSurfaceOffsetAlongItsNormal) {
  // Seed figs. 3.37-3.38: the ball's centre follows the target surface offset by R along its normal.
  // On a surface tilted by the displacement, the tip offset is w + R (sqrt(1 + |grad w|^2) - 1)
  // (flat nominal floor): checked against finite differences of the predicted surface.
  const double R = 12.5;
  const reduce::LightModel m = test::synthetic_model(R, reduce::ToolShape::Ball);
  online::PredictorSettings s;
  s.prior_scale = 1e6;
  s.reading_range = 10;
  online::Predictor predictor(m, s);
  const Eigen::VectorXd alpha = (Eigen::VectorXd(4) << 30, -20, 25, 10).finished();  // steep: slopes of a few percent
  std::mt19937 rng(4);
  for (double t : profile_times()) predictor.add_profile(t, {tool_at(m, t), 0.0}, profile(m, alpha, t, 0, rng, no_offset));
  ASSERT_TRUE(predictor.estimate().learned);
  const double t = 105.5;
  const Eigen::Vector3d tool = tool_at(m, t);
  const double h = 1e-3;
  const double w = predictor.target_altitude(tool.x(), tool.y(), t) - 8.0;
  const double gx = (predictor.target_altitude(tool.x() + h, tool.y(), t) - predictor.target_altitude(tool.x() - h, tool.y(), t)) / (2 * h);
  const double gy = (predictor.target_altitude(tool.x(), tool.y() + h, t) - predictor.target_altitude(tool.x(), tool.y() - h, t)) / (2 * h);
  const double expected = w + R * (std::sqrt(1 + gx * gx + gy * gy) - 1);
  std::printf("ball: w %.4f mm, slope %.4f, offset %.6f mm (flat would be %.6f)\n", w, std::hypot(gx, gy), predictor.predicted_offset(t), w);
  EXPECT_GT(std::hypot(gx, gy), 0.005);
  EXPECT_NEAR(predictor.predicted_offset(t), expected, 2e-4);
}

TEST(Predictor, IngestAndOffsetQueriesRunConcurrently) {
  // An acquisition thread adds profiles while a control thread queries offsets; the end state is the
  // one a sequential run reaches.
  const reduce::LightModel m = test::synthetic_model();
  const Eigen::VectorXd alpha = (Eigen::VectorXd(4) << 1, 2, 3, 4).finished();
  std::mt19937 rng(5);
  std::vector<std::vector<MeasuredPoint>> profiles;
  const auto times = profile_times();
  for (double t : times) profiles.push_back(profile(m, alpha, t, 0.05, rng, no_offset));
  online::Predictor sequential(m, {}), concurrent(m, {});
  for (std::size_t i = 0; i < times.size(); ++i) sequential.add_profile(times[i], {tool_at(m, times[i]), 0.0}, profiles[i]);
  std::atomic<bool> done{false};
  std::thread control([&] {
    double t = 0, sum = 0;
    while (!done.load()) sum += concurrent.tool_offset(t += 0.01);
    EXPECT_TRUE(std::isfinite(sum));
  });
  for (std::size_t i = 0; i < times.size(); ++i) concurrent.add_profile(times[i], {tool_at(m, times[i]), 0.0}, profiles[i]);
  done = true;
  control.join();
  EXPECT_LT((sequential.estimate().alpha - concurrent.estimate().alpha).cwiseAbs().maxCoeff(), 1e-12);
}

namespace {

// The stock's top where the tool has not been: its nominal altitude plus w_top, from the top's own
// histories interpolated on the top's faces; NaN where the tool has reached any node of the face
// (the material there is being cut) or off the top.
double top_reading(const reduce::LightModel& m, const Eigen::VectorXd& alpha, double x, double y, double t) {
  const auto p = m.top.locate(x, y);
  if (!p) return std::nan("");
  double z = m.top.nominal_altitude(*p);
  for (int q = 0; q < p->count; ++q) {
    const int node = p->nodes[static_cast<std::size_t>(q)];
    if (m.top_cut_time[node] <= t) return std::nan("");
    for (int k = 0; k < m.rank(); ++k) z += alpha[k] * p->weights[static_cast<std::size_t>(q)] * m.top_histories[static_cast<std::size_t>(k)].at(node, t);
  }
  return z;
}

// A profile as the sensor sees it with the top: the floor where the tool cut, the top elsewhere.
std::vector<MeasuredPoint> profile_with_top(const reduce::LightModel& m, const Eigen::VectorXd& alpha, double t, double noise, std::mt19937& rng) {
  std::vector<MeasuredPoint> pts = profile(m, alpha, t, noise, rng, no_offset);
  std::normal_distribution<double> gauss(0, noise);
  for (auto& p : pts)
    if (std::isnan(p.z)) {
      const double z = top_reading(m, alpha, p.x, p.y, t);
      p.z = std::isnan(z) ? z : z + (noise > 0 ? gauss(rng) : 0);
    }
  return pts;
}

}  // namespace

TEST(Predictor, ReadsTheStockTopAsAnAbsoluteMeasurement) {
  // Noise-free readings of the unmachined top alone (the rim and ahead of the cut, no floor): the
  // top's w is sum alpha_k U1_top_k, so alpha is recovered as from the floor.
  reduce::LightModel m = test::synthetic_model();
  test::add_synthetic_top(m);
  online::PredictorSettings s;
  s.prior_scale = 1e6;
  online::Predictor predictor(m, s);
  const Eigen::VectorXd alpha = (Eigen::VectorXd(4) << 0.8, -1.3, 0.4, 2.1).finished();
  int used = 0, used_top = 0;
  for (double t : profile_times()) {
    const Eigen::Vector3d tool = tool_at(m, t);
    std::vector<MeasuredPoint> pts;
    for (int i = 0; i < 400; ++i) {
      const double x = tool.x() + 30, y = -15 + 130.0 * i / 399;  // ahead of the tool, across the part
      pts.push_back({x, y, top_reading(m, alpha, x, y, t)});
    }
    const auto r = predictor.add_profile(t, {tool, 0.0}, pts);
    used += r.used, used_top += r.used_top;
  }
  const double alpha_error = (predictor.estimate().alpha - alpha).cwiseAbs().maxCoeff() / alpha.cwiseAbs().maxCoeff();
  std::printf("top alone: %d points used, alpha error %.2e (relative)\n", used, alpha_error);
  EXPECT_GT(used, 5000);
  EXPECT_EQ(used_top, used);
  EXPECT_LT(alpha_error, 1e-8);

  // Readings of the top where the tool has been are not taken for the top (nor the floor: off it).
  online::Predictor fresh(m, s);
  const double t = 10;
  const Eigen::Vector3d tool = tool_at(m, t);
  const std::vector<MeasuredPoint> pts = {{tool.x() - 20, -10, 10.0},   // the rim beside a cut strip: a face the tool reached
                                          {tool.x() + 40, 60, 10.0},    // uncut top over the pocket
                                          {210, 110, 10.0}};            // the rim, never cut
  const auto r = fresh.add_profile(t, {tool, 0.0}, pts);
  EXPECT_EQ(r.used_top, 2);
  EXPECT_EQ(r.outside, 1);
}

TEST(Predictor, TheStockTopNarrowsTheEstimate) {
  // The same noisy profiles, floor and top, fitted with and without the top: the top's absolute
  // readings must shrink the posterior (the final shape's sd) and the estimate must stay within it.
  reduce::LightModel m = test::synthetic_model();
  test::add_synthetic_top(m);
  const Eigen::VectorXd alpha = (Eigen::VectorXd(4) << 0.8, -1.3, 0.4, 2.1).finished();
  std::mt19937 rng(7);
  std::vector<double> times;
  for (double t : profile_times())
    if (t < 45) times.push_back(t);  // two passes: the floor alone says little yet
  std::vector<std::vector<MeasuredPoint>> profiles;
  for (double t : times) profiles.push_back(profile_with_top(m, alpha, t, 0.05, rng));
  online::PredictorSettings with, without;
  without.use_stock_top = false;
  online::Predictor a(m, with), b(m, without);
  for (std::size_t i = 0; i < times.size(); ++i) {
    a.add_profile(times[i], {tool_at(m, times[i]), 0.0}, profiles[i]);
    b.add_profile(times[i], {tool_at(m, times[i]), 0.0}, profiles[i]);
  }
  const online::FinalShape sa = a.final_shape(), sb = b.final_shape();
  const double sd_with = sa.sd.row(2).maxCoeff(), sd_without = sb.sd.row(2).maxCoeff();
  const Eigen::VectorXd truth = m.final_basis * alpha;
  double worst_z = 0;
  for (Eigen::Index n = 0; n < sa.nodes.cols(); ++n) worst_z = std::max(worst_z, std::abs(sa.displacement(2, n) - truth[3 * n + 2]) / sa.sd(2, n));
  const online::Estimate e = a.estimate();
  const double mahalanobis2 = (e.alpha - alpha).dot(e.covariance.ldlt().solve(e.alpha - alpha));
  std::printf("final shape sd: %.2e mm with the top, %.2e mm without; worst node %.2f sd off; alpha Mahalanobis^2 %.2f (4 dof)\n", sd_with, sd_without, worst_z,
              mahalanobis2);
  EXPECT_LT(sd_with, 0.5 * sd_without);
  EXPECT_LT(mahalanobis2, 18.5);  // chi-square, 4 dof: exceeded with probability 1e-3
}

// The reader bounds a model's numbers (finding 26); a model built in memory past them, whose prior
// gives an infinite bound on the commanded offset, is refused rather than let any offset through.
TEST(Predictor, AModelWithNoFiniteOffsetBoundIsRefused) {
  reduce::LightModel model = test::synthetic_model();
  model.prior_sd[0] = 1e200;  // a variance of 1e400
  EXPECT_THROW(online::Predictor{model}, std::invalid_argument);
  online::PredictorSettings bounded;
  bounded.max_offset = 0.5;  // a bound given by the user stands, whatever the prior
  EXPECT_EQ(online::Predictor(model, bounded).max_offset(), 0.5);
}
