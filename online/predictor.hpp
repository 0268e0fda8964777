#pragma once
// The online predictor (docs/design.md §6): laser profiles in, tool-length offsets and the final shape out.
//
// Measurement model. Where the tool cut (x, y) at program time t_cut, with commanded tip altitude
// z_cmd = S0(x, y) + (offset applied at t_cut), a laser point read at program time t is
//   z = z_cmd + w(x, y, t) - w(x, y, t_cut) + noise,   w = sum_k alpha_k U1_k,
// so m = z - z_cmd is linear in alpha through the differenced basis U1_k(x, y, t) - U1_k(x, y, t_cut).
// Where the tool has not been (the stock's top, ahead of the cut and around the pocket), when the
// model carries the top, a point reads the top's nominal altitude plus its w since machining began:
//   z = S0_top(x, y) + w_top(x, y, t) + noise,   w_top = sum_k alpha_k U1_top_k,
// an absolute measurement of the same alpha, where the floor's is a difference since the cut.
// The fit is Bayesian least squares: normal equations accumulated profile by profile (cost
// independent of what came before), a Gaussian prior on alpha from the model (its prior covariance, or diag(prior_sd^2))
// (a profile with independent coefficients of standard deviation profile_scale), and the posterior
// covariance (H / sigma^2 + prior^-1)^-1, which gives every prediction its standard deviation.
//
// Times are program times: when the tool reaches a point running at the programmed feed. Mapping the
// controller's clock to it (waypoint edges, dead reckoning) is the synchronizer's job.
//
// Threads: one acquisition thread calls add_profile; one control thread calls tool_offset (which
// keeps the rate limiter's state); any thread may call the const queries. The estimate is published
// as an immutable snapshot, so a query never waits for a profile being ingested.
//
// A hostile stream (docs/robustness.md) is never an error: what is not a usable measurement is
// counted by reason (rejections()) and left out, and the commanded offset always moves at most
// max_offset_rate and stays within max_offset.
//   Points: non-finite coordinates, off the part, not yet cut, or beyond reading_range of the fit's
//   prediction (a wall, a chip) are dropped and counted in the profile's report.
//   Profiles: a non-finite time or offset; older than, or at the time of, the last profile taken; the
//   very same points as the last profile taken (a frozen sensor); none usable; and, once learned, a
//   profile whose median residual is off the fit by more than glitch_sigmas of its predictive
//   spread, plus the model's error bound and the learning tolerance (coolant on the sheet, a sensor
//   that suddenly reads off): rejected and counted.
//   Recovery: before learning no offset is commanded, and a burst that got into the fit only delays
//   the learning (recent profiles must be predicted within the tolerance). After learning, a run of
//   glitch_run glitches in a row puts the fit in doubt: the sensor may be off, or the part may have
//   left the fit, and nothing in the readings alone tells which. In doubt, no offset is commanded (it
//   returns to 0 at the rate limit, and the machine runs its program as written), and the trusted
//   fit (as before the run) keeps scoring every profile by the same test: learning_window judged
//   profiles in a row within the allowance end the doubt, the profiles it predicted join the fit,
//   and the run leaves no trace. A sensor that stays off is never fitted and never corrected for; a
//   part that truly left the fit is not followed either (it is reported: rejections().unlearned,
//   summary.json's loop.rejected).
#include "reduce/cut_time.hpp"
#include "reduce/light_model.hpp"

#include <Eigen/Core>

#include <array>
#include <atomic>
#include <limits>
#include <memory>
#include <mutex>
#include <span>
#include <vector>

namespace drom::online {

struct MeasuredPoint {
  double x = 0, y = 0, z = 0;  // part frame, mm; z NaN: the sensor saw nothing
};

struct ToolPose {
  Eigen::Vector3d tip = Eigen::Vector3d::Zero();  // programmed tool tip when the profile was taken
  double applied_offset = 0;                      // tool-length offset in force then (mm)
};

struct PredictorSettings {
  double noise_sd = 0.05;           // mm: the sensor's noise (sigma of the measurement model)
  double prior_scale = 1;           // multiplies the model's prior standard deviations
  double reading_range = 1.0;       // mm: a reading this far from the fit's prediction is not the machined surface (a wall, the stock's top, a glitch)
  double learning_tolerance = 0.01; // mm: learned once the fit predicts recent points this well (net of noise)
  int learning_window = 5;          // profiles the learning criterion looks back on
  double max_offset_rate = 1.0;     // mm/s of program time: rate limit of the commanded offset
  double path_sample = 2.0;         // mm between the precomputed samples of the path's offsets
  bool use_stock_top = true;        // fit readings of the stock's top too (when the model has it)
  double top_noise_sd = -1;         // mm: sigma of those readings; <= 0: noise_sd
  double max_offset = -1;           // mm: bound on the commanded offset; <= 0: the prior's mean + 4 sd of the offset along the path
  double glitch_sigmas = 6;         // a learned fit rejects a profile whose median residual is off by this many predictive sd (plus margins)
  int glitch_run = 20;              // this many glitch rejections in a row put the fit in doubt (the class comment)
};

// What a stream held that was not a usable measurement, counted by reason (the class comment).
struct Rejections {
  long long non_finite = 0;    // profiles with a non-finite time or applied offset
  long long out_of_order = 0;  // profiles older than the last one taken
  long long repeated = 0;      // profiles at the time of the last one taken
  long long stuck = 0;         // profiles with the very same points as the last one taken
  long long empty = 0;         // profiles with no usable point
  long long glitch = 0;        // profiles as a whole off a learned fit
  long long unlearned = 0;     // times a run of glitch_run glitches put the fit in doubt (no offset until resolved)
  long long doubts_resolved = 0; // doubts resolved: the trusted fit predicted the stream again, the run left no trace
  long long offsets_non_finite = 0;  // record_offset calls with a non-finite time or offset
  long long offsets_late = 0;        // record_offset calls older than the last offset recorded (taken, in their place)
  long long offsets_clamped = 0;     // tool_offset calls whose target passed max_offset
};

struct ProfileReport {
  const char* rejected = nullptr;  // why the whole profile was left out (nullptr: taken); see Rejections
  int used = 0, outside = 0, not_yet_cut = 0, invalid = 0, out_of_range = 0;
  int used_top = 0;           // of `used`, readings of the stock's top (the rest are of the machined floor)
  double predictive_rms = 0;  // of the used points against the fit before they were added (mm)
};

struct Estimate {
  Eigen::VectorXd alpha;
  Eigen::MatrixXd covariance;
  long long points = 0;
  int profiles = 0;
  bool learned = false;
};

struct FinalShape {
  Eigen::Matrix3Xd nodes;         // nominal positions of the final part's surface nodes
  Eigen::Matrix3Xd displacement;  // predicted, mm
  Eigen::Matrix3Xd sd;            // its pointwise standard deviation, mm
  std::vector<int> faces;
  int face_nodes = 4;
};

enum class Verdict { WithinTolerance, StraighteningNeeded, Scrap };
const char* verdict_name(Verdict v);

struct ShapeTolerances {
  double tolerance = 0.1;            // mm: |normal displacement| the part may keep
  double straightening_limit = 1.0;  // mm: beyond this, straightening cannot save it
  double confidence = 1.96;          // standard deviations added (or removed) before deciding
};

class Predictor {
 public:
  Predictor(reduce::LightModel model, PredictorSettings settings = {});

  // One laser profile read at program time t. Points off the target surface, not yet cut, NaN, or
  // out of range are dropped and counted.
  // pose.applied_offset is taken as in force from t on; where the offset changed between profiles,
  // record_offset gives the exact instant (the commanded altitude where points were cut depends on it).
  ProfileReport add_profile(double t, const ToolPose& pose, std::span<const MeasuredPoint> points);
  void record_offset(double t, double offset);
  Estimate estimate() const;
  // Whether the learning phase is over (from the published snapshot: no solve, no lock).
  bool learned() const { return snapshot()->learned; }

  // Predicted altitude of the target surface at (x, y) and program time t (NaN off the surface), and
  // its standard deviation.
  double target_altitude(double x, double y, double t) const;
  double target_altitude_sd(double x, double y, double t) const;
  // Offset that puts the tool on the predicted target surface at program time t (the tool where the
  // program has it then): w for a flat end mill; for a ball end mill the centre rides the surface
  // offset by R along its normal, w + R (sqrt(1 + |grad S|^2) - sqrt(1 + |grad S0|^2)) (seed figs.
  // 3.37-3.38). The vertical offset is the same whether the program gives the tool tip or the ball's
  // centre: add it to whichever the program gives. 0 until learned.
  double predicted_offset(double t) const;
  // Its standard deviation under the fit's posterior (linearized in alpha for ball end mills); 0
  // until learned, as the offset.
  double predicted_offset_sd(double t) const;
  // predicted_offset rate-limited from the last value returned (control thread only).
  double tool_offset(double t);
  double commanded_altitude(double t, double programmed_z) { return programmed_z + tool_offset(t); }

  FinalShape final_shape() const;
  Verdict verdict(const ShapeTolerances& tolerances) const;

  Rejections rejections() const;
  double max_offset() const { return max_offset_; }

  const reduce::LightModel& model() const { return model_; }
  const PredictorSettings& settings() const { return settings_; }

 private:
  struct Snapshot {
    Eigen::VectorXd alpha;
    Eigen::MatrixXd covariance;
    bool learned = false;
  };
  // d(offset)/d(alpha) at path sample i, for the fit alpha.
  Eigen::RowVectorXd offset_gradient(Eigen::Index i, const Eigen::VectorXd& alpha) const;
  Eigen::RowVectorXd basis_at(const reduce::SurfacePoint& p, double t) const;  // U1_k(x, y, t), k = 1..r
  double applied_offset_at(double t) const;
  void set_offset(double t, double offset);
  std::shared_ptr<const Snapshot> snapshot() const { return snapshot_.load(std::memory_order_acquire); }

  reduce::LightModel model_;
  PredictorSettings settings_;
  int r_ = 0;
  Eigen::MatrixXd prior_precision_;
  Eigen::VectorXd prior_rhs_;  // prior precision x prior mean
  // Path samples for the offsets: program time, and per sample U1_k and its x / y derivatives at the
  // tool's position, plus the nominal surface's slope there (ball end mills).
  Eigen::VectorXd sample_time_;
  Eigen::MatrixXd sample_w_, sample_wx_, sample_wy_;  // samples x r
  Eigen::VectorXd sample_inside_, sample_s0x_, sample_s0y_;

  // When the tool cut any point of the target (a face's nodes may have been cut passes apart, so the
  // differenced basis is taken at the point's own cut time, not interpolated from its nodes').
  reduce::CutTimeIndex cut_index_;

  mutable std::mutex ingest_;
  // add_profile's scratch (under ingest_). U1 at a node and a stored instant j, all r modes, kept in
  // a small per-node cache (slot j mod kSlots): a profile touches a few instants per node (its own
  // time interval, and the cut times of the two or three passes under the sheet).
  static constexpr int kSlots = 32;
  struct InstantCache {
    std::vector<Eigen::MatrixXd> space_by_node;  // per mode: its space factors, terms x nodes
    std::vector<Eigen::MatrixXd> time_by_instant;  // and its time factors, terms x instants
    Eigen::MatrixXd values;                      // r x (nodes * kSlots)
    std::vector<Eigen::Index> tag;               // the instant each slot holds (-1: none)
    void reset(const std::vector<reduce::SpaceTimeField>& h, int nodes);
    const double* at(int node, Eigen::Index j);
  };
  using RowMatrix = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
  // One face under one gather: its nodes' U1 rows at the profile's time (count x r, blended once,
  // since a profile's points cross a face one after the other) and, for the lowest-cut search,
  // w = U1 . alpha at its nodes at each instant asked for so far.
  struct FaceMemo {
    int face = -1;
    RowMatrix rows_now;
    std::vector<std::pair<Eigen::Index, std::array<double, 9>>> w;
    // The face's nodes' differenced rows for a cut in (instant i, i + 1): U1(t) - U1(i) and
    // U1(i + 1) - U1(i). The points of a face that one cover cut mostly share i, so a point's row is
    // one blend of these instead of three of the per-node cache's.
    struct CutRows {
      Eigen::Index instant = -1;
      RowMatrix since, step;
    };
    std::array<CutRows, 2> cut;  // the two instants asked for last (a face under two passes' cuts)
    std::size_t older = 0;
    // sum_q N_q U1(node_q, t) at a point of the face: its row at the profile's time.
    void row_at(const reduce::SurfacePoint& p, double* out) const;
  };
  // The stored instant after i, the other end of a blend between instants (i itself when the model
  // has a single instant).
  Eigen::Index next_instant(Eigen::Index i) const;
  void enter_face(InstantCache& cache, const reduce::SurfacePoint& p, const reduce::TimeInterval& now, FaceMemo& memo);
  // w at the face's nodes at instant j for the fit alpha (target surface); valid until the next call.
  const double* face_w(FaceMemo& memo, const reduce::SurfacePoint& p, Eigen::Index j, const Eigen::VectorXd& alpha);
  // The face's differenced rows for a cut between instants i and i + 1 (target surface).
  const FaceMemo::CutRows& cut_rows(FaceMemo& memo, const reduce::SurfacePoint& p, Eigen::Index i);
  std::vector<std::pair<double, double>> covers_;
  std::vector<reduce::CutPieceEnd> candidates_;
  InstantCache target_cache_, top_cache_;
  FaceMemo floor_memo_, top_memo_;
  double top_weight_ = 1;                       // sigma_floor / sigma_top: a top row's scale in the shared normal equations
  Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor> G_;  // the profile's differenced basis, points x r
  Eigen::VectorXd m_;                           // and its readings net of the commanded altitude
  Eigen::MatrixXd normal_;  // sum g g^T / sigma^2
  Eigen::VectorXd rhs_;     // sum g m / sigma^2
  long long points_ = 0;
  int profiles_ = 0;
  double last_profile_time_ = 0, last_record_time_ = -std::numeric_limits<double>::infinity();
  bool seen_profile_ = false;
  std::vector<MeasuredPoint> last_points_;  // the last profile taken (a frozen sensor repeats it)
  Rejections rejections_;                   // under ingest_, but for offsets_clamped (control thread)
  std::atomic<long long> offsets_clamped_{0};
  // Profiles' shares of the normal equations, held apart from the fit while it is in doubt: those the
  // trusted fit predicts (kept_), which join it when the doubt ends.
  struct Share {
    Eigen::MatrixXd normal;
    Eigen::VectorXd rhs;
    long long points = 0;
    int profiles = 0;
    Share& operator+=(const Share& o);
    static Share zero(int r);
  };
  Share kept_;
  bool in_doubt_ = false;
  int glitches_in_a_row_ = 0, agree_trusted_ = 0;
  double max_offset_ = 0;
  std::vector<double> recent_square_error_, recent_count_;  // per recent profile
  reduce::OffsetHistory offsets_;                           // the applied offset over program time
  bool learned_ = false;
  std::atomic<std::shared_ptr<const Snapshot>> snapshot_;

  double last_offset_ = 0, last_offset_time_ = 0;
  bool offset_started_ = false;
};

}  // namespace drom::online
