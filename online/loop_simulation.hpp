#pragma once
// The closed loop of docs/design.md §6-§7, simulated: a machine runs the program with the tool-length
// offset the predictor commands, a laser sheet on its spindle reads the floor it has cut as the part
// distorts, the predictor learns from the readings, and the part is the truth run's.
//
// Clocks. Without a machine model the machine runs in clock time at feed_override x the programmed
// feed, so it is at program time t_true = feed_override * clock. With one (machine_motion), it moves
// as the machine's kinematic model predicts (machine/feed_prediction.hpp: slower into corners and at
// the ends of passes), and t_true is the program time of the point it has reached. The predictor only
// knows the controller's waypoint edges, late by `desync`, and dead-reckons the program time
// t_believed in between, at the programmed feed or with `reckoning_motion`: the sensor's points are
// placed, and offsets are computed, for the believed time.
//
// Each step (the smaller of the sensor period and the offset refresh interval):
//   1. the tool, where it truly is, cuts at its commanded altitude (programmed z + applied offset);
//      the altitude error of the tool-workpiece contact point against the ideal path (the program
//      moved with the true target surface) is the applied offset minus the one the truth needed;
//   2. on the refresh instants, the offset for the middle of the coming hold interval is commanded;
//   3. on the sensor instants, a profile is read from the true surfaces and handed to the predictor.
// At the end of every pass the predictor's final shape is compared with the truth's.
#include "online/dead_reckoning.hpp"
#include "online/laser_sheet.hpp"
#include "online/machined_floor.hpp"
#include "online/predictor.hpp"
#include "online/surface_history.hpp"

#include <Eigen/Core>

#include <cstdint>
#include <functional>
#include <memory>
#include <random>
#include <optional>
#include <vector>

namespace drom::online {

// The real part, as the simulation needs it.
struct TruePart {
  const SurfaceHistory* target = nullptr;  // w of the target surface over program time (mm)
  const SurfaceHistory* top = nullptr;     // w of the stock's top (on the model's top mesh); none: the top reads as not moving
  // Program time each top node is cut (its values are held from then on). Where a top face has a cut
  // node, the stock still standing over the pocket is read through the floor-level point below it.
  const Eigen::VectorXd* top_cut_time = nullptr;
  Eigen::Matrix3Xd final_displacement;     // after unclamping, at the model's final-shape nodes (mm)
  // Nominal altitude of the stock's top at (x, y); nothing off the part.
  std::function<std::optional<double>(double, double)> stock_top;
};

// What the sheet truly reads at (x, y) at true program time t: the floor the tool cut there; else
// the stock's top, moved by the truth's own top where that top face still stands whole, and by the
// floor-level w below it where the face is partly cut (its held values belong to removed material,
// while the column under the point is intact) or where the truth has no top; nothing off the part.
// `hint`, `top_hint`: the faces of the last point read (a profile's points mostly share one).
std::optional<double> true_height(const TruePart& truth, const reduce::SurfaceMesh& target, const MachinedFloor& floor, double x, double y, double t, int& hint,
                                  int& top_hint);

struct LoopSimulationSettings {
  LaserSheet sheet;
  SensorErrors errors;
  double period = 0.1;         // s between profiles
  double refresh_rate = 10;    // Hz: offset setpoints
  double desync = 0;           // s: how late the controller's edges reach the predictor
  double feed_override = 1;    // the machine's feed over the programmed one
  std::vector<int> sync;       // waypoints raising an edge; empty: every waypoint
  bool correct = true;         // false: the offsets stay 0 (the predictor still learns)
  std::uint32_t seed = 2015;   // the sensor noise's
  // The machine's real motion along the model's path (at feed_override); null: the programmed feed.
  std::shared_ptr<const machine::ProgramClock> machine_motion;
  // The synchronizer's model of that motion between edges (it does not know the override); null:
  // the programmed feed.
  std::shared_ptr<const machine::ProgramClock> reckoning_motion;
};

// How far the synchronizer's believed position lay from the tool's, over the steps on the floor: the
// program time error, and the shift along the path it amounts to (the seed's feed x Δt, §2.3.4).
struct SyncError {
  long long samples = 0;
  double max_time = 0, max_shift = 0, rms_shift = 0;  // s of program time, mm
  void add(double time_error, double shift);
  void finish();
};

// A pass: a stretch of program time with the tool on the floor (on the target surface, at depth).
struct Pass {
  double start = 0, end = 0;
};
std::vector<Pass> floor_passes(const reduce::LightModel& model);

struct LoopSample {                    // one step with the tool on the floor
  double clock = 0, program_time = 0;  // true program time
  double x = 0, y = 0;
  double offset = 0;                   // applied (mm)
  double offset_sd = 0;                // the predictor's standard deviation of the offset it would command now (mm)
  double distortion = 0;               // w_true under the tool (mm)
  double error = 0;                    // offset applied - offset the true target needed: the contact point against the ideal path (mm)
  int pass = 0;                        // 1-based
  bool learned = false;
};

struct PassFigures {
  int pass = 0;
  double start = 0, end = 0;  // program time
  int samples = 0;
  double mean_abs_error = 0, max_abs_error = 0;        // path altitude error (mm)
  double max_abs_distortion = 0;                       // w_true under the tool (what no correction leaves)
  // The final-shape prediction at the pass's end against the truth, on the vertical displacement of
  // the final part's surface nodes: max and RMS error, and the fraction inside the 95 % band.
  double shape_max_error = 0, shape_rms_error = 0, shape_band_coverage = 0;
  bool learned = false;  // the predictor was learned by the pass's end
  long long profiles = 0, points_used = 0;
};

struct OffsetCommand {
  double clock = 0, believed_time = 0, true_time = 0, offset = 0;
};

// What a calibration error does to the measured surface (seed §2.3.2): at every tenth profile's
// points on the floor, the reading's bias (the floor where the sheet truly is minus the floor where
// it is believed to be, noise-free) against the local slope times the sheet's displacement.
struct CalibrationBias {
  long long points = 0;
  double rms_bias = 0, rms_slope_times_offset = 0;  // mm
  double ratio = 0;  // least-squares slope of bias on slope x offset (1: the seed's rule holds)
};

struct LoopSimulationResult {
  std::vector<LoopSample> samples;
  std::vector<PassFigures> passes;
  std::vector<FinalShape> shapes;  // the prediction at each pass's end
  std::vector<Estimate> estimates; // and the fit it came from
  std::vector<OffsetCommand> offsets;
  double learned_at = -1;          // program time (true) at which the predictor declared itself learned
  long long profiles = 0;
  ProfileReport points;            // totals over all profiles
  Rejections rejections;           // what the predictor left out, by reason
  double offset_bound = 0;         // mm: the bound the commanded offset was held within
  Estimate estimate;               // at the end
  CalibrationBias calibration;     // empty without calibration errors
  SyncError sync;                  // the synchronizer's, as run
  SyncError sync_programmed_feed;  // what a synchronizer reckoning at the programmed feed would have had
  double seconds = 0;
};

// The closed loop's world, stepped in the controller's clock: the machine moving the tool along the
// program (at the feed override), the program's waypoint edges reaching the synchronizer (late by the
// desync), the real part under the tool, the floor the tool cuts with the offsets commanded, and the
// laser sheet on the spindle (its calibration errors and noise). A controller drives it: at each step
// it commands an offset when a refresh falls due and takes the profile the sheet reads when a scan
// does. LoopSimulation::run is that controller with a Predictor; the Python module drives the same
// machine with its own (so both give the same errors, bit for bit).
class LoopMachine {
 public:
  // `truth` must outlive the machine.
  LoopMachine(const reduce::LightModel& model, const TruePart& truth, LoopSimulationSettings settings);

  struct Step {
    long index = 0;
    double clock = 0;          // controller time (s)
    double true_time = 0;      // program time the tool has truly reached
    double believed_time = 0;  // program time the synchronizer believes
    double programmed_feed_time = 0;  // what it would believe reckoning at the programmed feed
    Eigen::Vector3d tip = Eigen::Vector3d::Zero(), believed_tip = Eigen::Vector3d::Zero();
    int pass = 0;              // 1-based pass the tool is on the floor in; 0: off the floor
    bool on_target = false;    // the tool is over the target surface on a pass: `sample` holds its error
    LoopSample sample;         // with the offset in force before this step's refresh
    bool refresh = false;      // a setpoint is due: command() it, for program time `setpoint_time`
    double setpoint_time = 0;  // believed program time in the middle of the interval the setpoint holds
    bool scan = false;         // a profile is due: scan()
  };

  long steps() const { return steps_; }  // steps 0 .. steps()
  // The clock time at which the tool reaches program time t (true motion), and the reverse.
  double clock_at(double program_time) const;
  double program_time_at(double clock) const;
  // Moves to step k (in order from 0).
  Step advance(long k);
  // The offset commanded at the current step, in force from its true program time on.
  void command(double offset);
  double applied() const { return applied_; }
  // The profile the sheet reads at the current step: heights where the sheet truly is, placed where
  // the synchronizer believes it is.
  std::vector<MeasuredPoint> scan();

  const std::vector<Pass>& passes() const { return passes_; }
  CalibrationBias calibration() const;
  const TruePart& truth() const { return truth_; }

 private:
  const reduce::LightModel& model_;
  const TruePart& truth_;
  LoopSimulationSettings settings_;
  std::vector<Pass> passes_;
  std::vector<int> sync_;
  std::unique_ptr<DeadReckoning> reckoning_, programmed_reckoning_;
  std::unique_ptr<MachinedFloor> floor_;
  std::mt19937 rng_;
  double step_ = 0;
  long scan_every_ = 1, refresh_every_ = 1, steps_ = 0;
  std::size_t next_edge_ = 0;
  long profiles_ = 0;
  Step current_;
  double applied_ = 0;
  bool calibrating_ = false;
  double sum_be_ = 0, sum_ee_ = 0, sum_bb_ = 0;
  long long calibration_points_ = 0;
};

class LoopSimulation {
 public:
  LoopSimulation(const reduce::LightModel& model, PredictorSettings predictor, LoopSimulationSettings settings);
  LoopSimulationResult run(const TruePart& truth, const std::function<void(double fraction)>& progress = {}) const;

  const std::vector<Pass>& passes() const { return passes_; }

 private:
  const reduce::LightModel& model_;
  PredictorSettings predictor_settings_;
  LoopSimulationSettings settings_;
  std::vector<Pass> passes_;
};

}  // namespace drom::online
