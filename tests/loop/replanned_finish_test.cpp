// The finishing pass re-planned on a predicted final shape (drom run --replan) against closed forms:
// a 200 x 120 mm plate whose final shape bows by w(x, y) = 1.6 (1 - (2x/L)^2) mm (the flat plate's
// order of distortion), the prediction off by a known ripple e(x, y) of amplitude 3 µm. A ball
// dropped on the predicted cloud stands, everywhere, within the ripple's amplitude (plus the drop's
// sampling and curvature bounds, microns) of where it stands on the truth; the nominal path, dropped
// on the drawn plate, is off by the whole bow.
#include "loop/replanned_finish.hpp"

#include "tests/loop/plate_shape.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <numbers>

namespace {

drom::online::FinalShape plate(int nx, int ny, double lx, double ly) { return drom::test::plate_shape(nx, ny, lx, ly, -5); }

TEST(ReplannedFinish, FollowsThePredictedShapeWithinItsErrorWhereTheNominalPathIsOffByTheBow) {
  const double lx = 200, ly = 120, bow = 1.6, ripple = 0.003;
  drom::online::FinalShape shape = plate(40, 24, lx, ly);
  Eigen::Matrix3Xd truth = Eigen::Matrix3Xd::Zero(3, shape.nodes.cols());
  for (Eigen::Index k = 0; k < shape.nodes.cols(); ++k) {
    const double x = shape.nodes(0, k), y = shape.nodes(1, k);
    truth(2, k) = bow * (1 - std::pow(2 * x / lx, 2));
    shape.displacement(2, k) = truth(2, k) + ripple * std::sin(2 * std::numbers::pi * x / 50) * std::cos(2 * std::numbers::pi * y / 40);
  }
  drom::loop::ReplanSettings s;
  s.finishing.longitudinal_step = 2;  // coarse: a test
  s.finishing.scallop = 0.01;
  const auto r = drom::loop::replan_finish(shape, truth, s);
  std::printf("re-planned finish: %lld upward faces, %lld cloud points, %d passes, %lld cut nodes judged, %lld gaps\n", r.faces, r.cloud_points, r.replanned.passes,
              r.judged, r.replanned.gaps);
  std::printf("  distance to the truth: re-planned max %.5f mm (RMS %.5f), nominal max %.4f mm (RMS %.4f); the prediction's error %.4f mm\n", r.max_error,
              r.rms_error, r.nominal_max_error, r.nominal_rms_error, ripple);
  EXPECT_EQ(r.faces, 40 * 24);
  EXPECT_GT(r.judged, 1000);
  EXPECT_EQ(r.replanned.gaps, 0);
  // Within the prediction's error plus the bilinear faces' chord on the bow (1.6 x (5/100)^2 / 2 = 2 µm).
  EXPECT_LE(r.max_error, ripple + 0.002 + 1e-4);
  EXPECT_LE(r.max_error, 0.01);  // the check 5 bound
  // The nominal path is off by the bow, up to its full height (the plate's middle).
  EXPECT_NEAR(r.nominal_max_error, bow, 0.01);
}

}  // namespace
