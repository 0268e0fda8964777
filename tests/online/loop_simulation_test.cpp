// The closed loop (online/loop_simulation.hpp) on the synthetic model (tests/reduce/synthetic_model.hpp),
// with a truth inside its basis so that what is left is the loop's own doing:
//   - the simulated floor against an independent brute-force reading (tests/online/exact_reading.hpp);
//   - the loop is closed: without correction the floor error is the truth's distortion, with it the
//     error falls below the tolerance once learned (check 2 of the issue);
//   - a sensor calibration error along the feed biases the measured surface by slope x offset
//     (seed §2.3.2; check 3 of the issue).
#include "online/loop_simulation.hpp"
#include "online/machined_floor.hpp"
#include "tests/online/exact_reading.hpp"
#include "tests/reduce/synthetic_model.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>

using namespace drom;

namespace {

// The truth: the model's own histories combined with alpha, sampled at the model's instants.
struct Truth {
  Eigen::MatrixXd history;
  Eigen::VectorXd times;
  std::unique_ptr<online::SurfaceHistory> surface;
  online::TruePart part;
};

std::unique_ptr<Truth> truth_in_basis(const reduce::LightModel& m, const Eigen::VectorXd& alpha) {
  auto t = std::make_unique<Truth>();
  const Eigen::VectorXd& instants = m.histories.front().times();
  const Eigen::Index first = instants[0] > 0 ? 0 : 1;  // the start (w = 0) is the history's own
  t->times = instants.tail(instants.size() - first);
  t->history.setZero(m.target.node_count(), t->times.size());
  for (int k = 0; k < m.rank(); ++k)
    for (Eigen::Index s = 0; s < t->times.size(); ++s) t->history.col(s) += alpha[k] * m.histories[static_cast<std::size_t>(k)].at(t->times[s]);
  t->surface = std::make_unique<online::SurfaceHistory>(m.target, t->history, t->times);
  t->part.target = t->surface.get();
  const Eigen::VectorXd shape = m.final_basis * alpha;
  t->part.final_displacement = Eigen::Map<const Eigen::Matrix3Xd>(shape.data(), 3, m.shape_nodes.cols());
  t->part.stock_top = [](double x, double y) -> std::optional<double> {
    if (x < -50 || x > 250 || y < -50 || y > 150) return std::nullopt;
    return 10.0;
  };
  return t;
}

const Eigen::VectorXd kAlpha = (Eigen::VectorXd(4) << 1.6, -1.2, 0.9, 0.7).finished();

online::LoopSimulationSettings settings(bool correct, double noise) {
  online::LoopSimulationSettings s;
  s.errors.noise_sd = noise;
  s.refresh_rate = 100;
  s.correct = correct;
  return s;
}

online::PredictorSettings predictor(double noise) {
  online::PredictorSettings p;
  p.noise_sd = std::max(noise, 1e-4);
  p.learning_tolerance = 0.005;
  p.max_offset_rate = 2;
  return p;
}

}  // namespace

TEST(MachinedFloor, MatchesABruteForceReadingWithOffsetsChangingUnderTheTool) {
  const reduce::LightModel m = test::synthetic_model();
  const auto truth = truth_in_basis(m, kAlpha);
  online::MachinedFloor floor(m);
  // Offsets stepping every 0.37 s, so many change while the tool covers a point.
  std::vector<double> changes;
  for (double t = 0.37; t < 125; t += 0.37) changes.push_back(t);
  auto offset = [&](double t) {
    const auto k = std::upper_bound(changes.begin(), changes.end(), t) - changes.begin();
    return k == 0 ? 0.0 : 0.01 * std::sin(0.7 * static_cast<double>(k));
  };
  for (double c : changes) floor.command(c, offset(c));
  const Eigen::VectorXd& instants = truth->surface->times();
  const test::ExactReading exact(
      m, [&](const reduce::SurfacePoint& p, double t) { return truth->surface->at_instant(p, t); }, offset, changes,
      std::vector<double>(instants.data(), instants.data() + instants.size()));
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> x(0, 200), y(0, 100), t(0, 125);
  int compared = 0;
  double worst = 0;
  for (int i = 0; i < 3000; ++i) {
    const double px = x(rng), py = y(rng), pt = t(rng);
    const auto p = m.target.locate(px, py);
    ASSERT_TRUE(p);
    const double reference = exact(px, py, pt);
    const auto simulated = floor.surface(px, py, *p, *truth->surface, pt);
    ASSERT_EQ(std::isfinite(reference), simulated.has_value()) << "at (" << px << ", " << py << ") t = " << pt;
    if (!simulated) continue;
    worst = std::max(worst, std::abs(*simulated - reference));
    ++compared;
  }
  std::printf("machined floor: %d points on the floor, max difference from brute force %.2e mm\n", compared, worst);
  EXPECT_GT(compared, 1000);
  EXPECT_LT(worst, 1e-9);
}

// The sheet on the stock's top: the truth's own top where its face stands whole; where the tool has
// reached one of the face's nodes, those nodes' held values belong to removed material, and a point
// still standing over the pocket reads the floor-level w below it.
TEST(LoopSimulation, SheetReadsAPartlyCutTopFaceThroughTheFloorBelow) {
  reduce::LightModel m = test::synthetic_model();
  test::add_synthetic_top(m);
  const auto truth = truth_in_basis(m, kAlpha);
  const double top_w = 0.3;  // far from the floor's w, so that the two readings cannot be confused
  const Eigen::VectorXd& instants = m.histories.front().times();
  const online::SurfaceHistory top(m.top, Eigen::MatrixXd::Constant(m.top.node_count(), instants.size() - 1, top_w), instants.tail(instants.size() - 1));
  truth->part.top = &top;
  truth->part.top_cut_time = &m.top_cut_time;
  const online::MachinedFloor floor(m);
  int standing = 0, partly_cut = 0, checked_floor = 0;
  for (double t : {30.0, 60.0, 90.0}) {
    for (double y = -15; y <= 115; y += 2.5)
      for (double x = -15; x <= 215; x += 2.5) {
        int hint = -1, top_hint = -1;
        const auto z = online::true_height(truth->part, m.target, floor, x, y, t, hint, top_hint);
        ASSERT_TRUE(z.has_value());  // the synthetic stock covers the whole grid
        const auto p = m.target.locate(x, y);
        if (p && floor.surface(x, y, *p, *truth->part.target, t)) {
          ++checked_floor;
          continue;
        }
        const auto q = m.top.locate(x, y);
        ASSERT_TRUE(q.has_value());
        bool whole = true;
        for (int i = 0; i < q->count; ++i) whole = whole && m.top_cut_time[q->nodes[static_cast<std::size_t>(i)]] > t;
        if (whole || !p) {
          EXPECT_NEAR(*z, 10 + top_w, 1e-12) << x << ", " << y << " at " << t;
          standing += whole;
        } else {
          EXPECT_NEAR(*z, 10 + truth->part.target->at(*p, t), 1e-12) << x << ", " << y << " at " << t;
          ++partly_cut;
        }
      }
  }
  std::printf("sheet on the top: %d points on whole faces, %d on partly cut faces over the pocket, %d on the floor\n", standing, partly_cut, checked_floor);
  EXPECT_GT(standing, 100);
  EXPECT_GT(partly_cut, 100);
  EXPECT_GT(checked_floor, 100);
}

TEST(LoopSimulation, WithoutCorrectionTheErrorIsTheDistortionWithItBelowToleranceOnceLearned) {
  const reduce::LightModel m = test::synthetic_model();
  const auto truth = truth_in_basis(m, kAlpha);
  const double noise = 0.002, tolerance = 1e-3;
  const auto off = online::LoopSimulation(m, predictor(noise), settings(false, noise)).run(truth->part);
  const auto on = online::LoopSimulation(m, predictor(noise), settings(true, noise)).run(truth->part);
  ASSERT_EQ(off.passes.size(), 5u);
  // Without correction the tool stays on the program: the error is minus the distortion under it.
  double worst_follow = 0, largest = 0;
  for (const auto& s : off.samples) {
    worst_follow = std::max(worst_follow, std::abs(s.error + s.distortion));
    largest = std::max(largest, std::abs(s.distortion));
    EXPECT_EQ(s.offset, 0.0);
  }
  // With it, after learning (and the rate limit's catch-up), the error is under the tolerance.
  ASSERT_GE(on.learned_at, 0);
  double worst_after = 0;
  int after = 0;
  for (const auto& s : on.samples)
    if (s.program_time > on.learned_at + 2.0) worst_after = std::max(worst_after, std::abs(s.error)), ++after;
  std::printf("loop: distortion up to %.4f mm; uncorrected error follows it to %.1e; learned at %.1f s; corrected error after %.4f mm (%d samples)\n", largest,
              worst_follow, on.learned_at, worst_after, after);
  EXPECT_GT(largest, 0.02);
  EXPECT_LT(worst_follow, 1e-12);
  EXPECT_GT(after, 1000);
  EXPECT_LT(worst_after, tolerance);
  for (const auto& p : on.passes)
    std::printf("  pass %d: corrected max %.2e mean %.2e; final shape error %.2e mm, band coverage %.2f\n", p.pass, p.max_abs_error, p.mean_abs_error, p.shape_max_error,
                p.shape_band_coverage);
  std::printf("  alpha %s\n", [&] { std::string a; for (int k = 0; k < 4; ++k) a += std::to_string(on.estimate.alpha[k]) + " "; return a; }().c_str());
  // The final shape predicted at the end is the truth's, within the noise's reach.
  EXPECT_LT(on.passes.back().shape_max_error, 2e-3);
}

TEST(LoopSimulation, CalibrationOffsetAlongTheFeedBiasesTheSurfaceBySlopeTimesOffset) {
  const reduce::LightModel m = test::synthetic_model();
  const auto truth = truth_in_basis(m, 4 * kAlpha);  // steeper, so the bias stands out
  auto s = settings(false, 0);
  s.errors.offset_error = Eigen::Vector3d(1.0, 0, 0);  // 1 mm along the feed
  const auto r = online::LoopSimulation(m, predictor(0), s).run(truth->part);
  std::printf("calibration: %lld points, rms bias %.2e mm, rms slope x offset %.2e mm, ratio %.3f\n", r.calibration.points, r.calibration.rms_bias,
              r.calibration.rms_slope_times_offset, r.calibration.ratio);
  EXPECT_GT(r.calibration.points, 1000);
  EXPECT_GT(r.calibration.rms_bias, 1e-4);
  EXPECT_NEAR(r.calibration.ratio, 1.0, 0.2);
}
