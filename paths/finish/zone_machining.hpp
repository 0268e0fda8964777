#pragma once
// One zone finished with parallel planes, timed: its passes, the links between them and any
// retract where the next pass does not start next to the last one. Two accountings: the seed's
// (contact-point polylines, as Herraz measures them) and the machine's (the tool-tip polylines the
// machine really runs).
#include "paths/finish/move_time.hpp"
#include "paths/finish/parallel_planes.hpp"

#include <Eigen/Core>

#include <vector>

namespace drom::paths {

enum class Accounting {
  seed,     // the seed's: pass and link lengths along the contact points; no move between zones
  machine,  // the tool-tip (CL) polylines; retracts and moves between zones timed too
};

struct FinishingSettings {
  Tool tool;
  double scallop = 0.01;
  StepoverModel stepover = StepoverModel::curved;
  bool zigzag = true;
  bool exact = false;              // the exact (Newton) variant of the passes; else the seed's fast iso-line one
  double chord_tolerance = 2e-4;   // mm, the exact variant's chords
  double run_out = 0;              // mm, each pass continued past the zone's edges (PassSettings::run_out)
  Accounting accounting = Accounting::machine;
  // Times every pass, link and move (the seed's 5 m/min feed; rapids at 25 m/min).
  MoveTimer timer{Kinematics{}, Kinematics{25000.0 / 60, 6000, 40000}};
  double clearance = 5;  // mm above the highest point of a retract's ends
  double approach = 1;   // mm of a plunge at the cutting limits
  // A link longer than this many plane steps (and 2 mm) is a retract instead of a feed move.
  double link_steps = 5;
};

// How a zone is set on the machine: the part rotated by `rotation` (part frame -> machine frame,
// about `centre`) so the tool axis is the machine's Z, and fed along the machine-frame azimuth.
struct ZoneSetup {
  double azimuth = 0;
  Eigen::Matrix3d rotation = Eigen::Matrix3d::Identity();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();
  double zeta = 0;  // the PCA heuristic's tilt about the zone's X_II (informative; 0 for other setups)
  // The tool axis and the feed, in the part frame.
  Eigen::Vector3d axis() const { return rotation.transpose() * Eigen::Vector3d::UnitZ(); }
  Eigen::Vector3d feed() const;
  Eigen::Vector3d to_machine(const Eigen::Vector3d& part_point) const { return rotation * (part_point - centre) + centre; }
};

struct ZoneMachining {
  int zone = 0;
  ZoneSetup setup;
  std::vector<PlanePass> passes;
  // The polylines timed, machine frame, one per pass: tool tips (machine accounting) or contact points (the seed's).
  std::vector<std::vector<Eigen::Vector3d>> timed_lines;
  std::vector<bool> retract_before;  // per pass: the move into it is a retract (else a link; false for the first)
  double pass_time = 0, link_time = 0, retract_time = 0;
  double pass_length = 0, link_length = 0;
  int links = 0, retracts = 0;
  double time() const { return pass_time + link_time + retract_time; }
  int gouging_contacts() const;  // over its passes (PlanePass::gouging_contacts)
  double length() const { return pass_length + link_length; }
  // Where the tool enters and leaves the zone (machine frame).
  Eigen::Vector3d start() const { return timed_lines.front().front(); }
  Eigen::Vector3d end() const { return timed_lines.back().back(); }
};

ZoneMachining machine_zone(const MachiningMesh& mesh, const std::vector<int>& cells, int zone, const ZoneSetup& setup, const FinishingSettings& settings);

// The zone's passes run in the opposite order and direction (to start where another zone ends).
void reverse_zone(ZoneMachining& z);

}  // namespace drom::paths
