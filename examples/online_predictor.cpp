// drom example 3: a light model loaded, a Predictor fed laser profiles from an acquisition thread
// while a control thread asks it for tool-length offsets, as beside a running machine.
//
// Sample run:
//   online_predictor out/coarse_model/model.h5
//
// The part is simulated from the model itself: its distortion is a profile inside the basis (the
// prior's mean plus one standard deviation of each coefficient), the laser sheet reads the floor the
// tool has cut (online::MachinedFloor) without noise, and the predictor recovers the profile's
// coefficients. The program exits with 1 if they are not recovered to 1e-8 (relative), so the example
// doubles as a check of an installed drom (tests/library).
#include "online/laser_sheet.hpp"
#include "online/machined_floor.hpp"
#include "online/predictor.hpp"
#include "online/surface_history.hpp"
#include "reduce/light_model.hpp"
#include "support/input_error.hpp"

#include <atomic>
#include <cmath>
#include <cstdio>
#include <random>
#include <thread>

namespace {

// The tool tip on the model's programmed path at program time t.
Eigen::Vector3d tool_at(const Eigen::MatrixXd& path, double t) {
  Eigen::Index i = 0;
  while (i + 2 < path.rows() && path(i + 1, 3) <= t) ++i;
  const double t0 = path(i, 3), t1 = path(i + 1, 3);
  const double a = t1 > t0 ? std::clamp((t - t0) / (t1 - t0), 0.0, 1.0) : 0.0;
  return ((1 - a) * path.row(i).head<3>() + a * path.row(i + 1).head<3>()).transpose();
}

}  // namespace

int main(int argc, char* argv[]) {
  if (argc < 2) {
    std::fprintf(stderr, "usage: online_predictor MODEL.h5\n");
    return 2;
  }
  try {
    // 1. The light model (its format version is checked).
    const drom::reduce::LightModel model = drom::reduce::LightModel::read(argv[1]);
    const int r = model.rank();

    // 2. The part: a profile inside the basis, and its displacement of the target surface over the
    //    stations (the model's own space-time histories, so the truth is exactly representable).
    Eigen::VectorXd alpha = model.prior_sd;
    if (model.prior_mean.size() == r) alpha += model.prior_mean;
    const Eigen::VectorXd& instants = model.histories.front().times();  // the start, then the stations
    const Eigen::VectorXd stations = instants.tail(instants.size() - 1);
    Eigen::MatrixXd w = Eigen::MatrixXd::Zero(model.target.node_count(), stations.size());
    for (int k = 0; k < r; ++k)
      for (Eigen::Index j = 0; j < stations.size(); ++j) w.col(j) += alpha[k] * model.histories[static_cast<std::size_t>(k)].at(stations[j]);
    const drom::online::SurfaceHistory truth(model.target, w, stations, instants[0]);
    const drom::online::MachinedFloor floor(model);  // no offset applied: the floor as programmed

    // 3. The predictor: a noise-free sensor, so a prior that does not pull.
    drom::online::PredictorSettings settings;
    settings.prior_scale = 1e6;
    drom::online::Predictor predictor(model, settings);

    // 4. The acquisition thread: a profile every 0.1 s of program time, the sheet 50 mm ahead of the
    //    tool along x, across the feed.
    const double t_end = model.path(model.path.rows() - 1, 3);
    std::atomic<double> now{0};
    std::atomic<bool> done{false};
    std::thread acquisition([&] {
      drom::online::LaserSheet sheet;
      std::mt19937 rng(1);
      int hint = -1;
      for (double t = 0.1; t < t_end; t += 0.1) {
        const Eigen::Vector3d tip = tool_at(model.path, t);
        const auto heights = [&](double x, double y) -> std::optional<double> {
          const auto p = model.target.locate(x, y, hint);
          if (!p) return std::nullopt;
          hint = p->face;
          return floor.surface(x, y, *p, truth, t);
        };
        const auto points = drom::online::scan(sheet, {}, tip, tip, heights, rng);
        predictor.add_profile(t, {tip, 0.0}, points);
        now = t;
      }
      done = true;
    });

    // 5. The control thread (here, main): the rate-limited offset for where the tool is, at 100 Hz of
    //    program time, as the machine's controller would ask for it. This run only logs them (the
    //    floor is cut as programmed); applied, they would also go to the predictor's record_offset.
    double offset = 0, last = 0;
    int commands = 0;
    while (!done) {
      const double t = now.load();
      if (t >= last + 0.01) {
        offset = predictor.tool_offset(t);
        last = t;
        ++commands;
      } else {
        std::this_thread::yield();
      }
    }
    acquisition.join();

    // 6. What it learned: the coefficients, and the final shape with its band and verdict.
    const auto estimate = predictor.estimate();
    const double error = (estimate.alpha - alpha).cwiseAbs().maxCoeff() / alpha.cwiseAbs().maxCoeff();
    const auto shape = predictor.final_shape();
    std::printf("rank %d, %d profiles, %lld points; %d offsets commanded, the last %.4f mm\n", r, estimate.profiles, estimate.points, commands, offset);
    std::printf("coefficients recovered to %.2e (relative); final shape max |w| %.4f mm; verdict: %s\n", error, shape.displacement.row(2).cwiseAbs().maxCoeff(),
                drom::online::verdict_name(predictor.verdict({})));
    return error < 1e-8 ? 0 : 1;
  } catch (const drom::InputError& e) {
    std::fprintf(stderr, "online_predictor: %s\n", e.what());
    return 2;
  }
}
