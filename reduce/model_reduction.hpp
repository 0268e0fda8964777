#pragma once
// From the offline databases to the light model's bases (docs/design.md §5):
//   1. scale B1's unit-profile columns to a plausible amplitude (profile_scale MPa), so tolerances
//      and bounds are in mm of a plausible profile;
//   2. POD with the fewest modes whose max-norm bound (seed eq. 2.9) meets `tolerance`;
//   3. each basis history U1_k, reshaped target nodes x stations, kept as sum_l a_l(x) b_l(t) with
//      tolerance history_tolerance / r on sigma_k U1_k (so all histories together cost at most
//      history_tolerance in mm);
//   4. the stock's top likewise, U1_top = B1_top V_r D_r^-1 (the readings of material not yet
//      machined), compressed the same way;
//   5. U2 = B2 V_r D_r^-1 for the final shape, and the prior on alpha: the profile's coefficients c
//      independent with standard deviations profile_sd (MPa), so alpha = D_r V_r^T c / profile_scale
//      ~ N(0, D_r V_r^T diag(profile_sd / profile_scale)^2 V_r D_r); with every sd at profile_scale
//      that is N(0, D_r^2).
#include "reduce/light_model.hpp"

#include <Eigen/Core>

namespace drom::reduce {

struct SnapshotDatabase {
  Eigen::MatrixXd B1;           // (stations * target nodes) x profiles, row station * n_target + node
  Eigen::MatrixXd final_shape;  // (3 * shape nodes) x profiles: B2 on the final part's surface
  Eigen::VectorXd station_times;  // program time of each station (s)
  double program_start = 0;       // program time when machining starts (w = 0 there)
  // Optional: the stock's top face, (stations * top nodes) x profiles, row station * n_top + node, and
  // per top node the program time the tool first cut it (+inf: never). After that the node's w is
  // that of removed material and means nothing: it is held at its last value before the cut.
  Eigen::MatrixXd B1_top;
  Eigen::VectorXd top_cut_time;
};

struct ReductionSettings {
  double tolerance = 1e-3;          // mm
  double history_tolerance = 5e-4;  // mm
  double profile_scale = 50;        // MPa
  int max_rank = -1;                // -1: as many as the tolerance needs
  // Plausible amplitude of each database column's coefficient (MPa), for the prior; empty:
  // profile_scale for every one.
  Eigen::VectorXd profile_sd;
  // The expected coefficient of each column (MPa), the prior's mean; empty: 0.
  Eigen::VectorXd profile_mean;
};

struct ReductionReport {
  double measured_max_error = 0;   // max over database columns, stations, nodes of |model - database| (mm at profile_scale)
  double top_measured_max_error = 0;  // the same on the stock's top, where it is still there
  int history_terms = 0;           // sum over the r histories of their separated terms
  double seconds = 0;
};

// A nodal history (nodes x stations) from each node's cut time on: held at its last value before the
// cut (after it, the node's w is that of removed material). The model's top and the closed loop's
// truth of it both follow this rule.
void hold_after_cut(Eigen::Ref<Eigen::MatrixXd> history, const Eigen::VectorXd& station_times, const Eigen::VectorXd& cut_time);

// Fills `model`'s bases, singular values, bounds and prior from the database (its surfaces, path and
// tool come from the caller).
ReductionReport reduce_snapshots(const SnapshotDatabase& db, const ReductionSettings& settings, LightModel& model);

}  // namespace drom::reduce
