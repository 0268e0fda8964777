#pragma once
// A whole surface finished zone by zone: each zone's passes (zone_machining.hpp), the zones put in
// an order that keeps the moves between them short, and the time and length broken down into
// passes, links, retracts and moves between zones.
#include "paths/finish/clustering.hpp"
#include "paths/finish/machining_mesh.hpp"
#include "paths/finish/pca.hpp"
#include "paths/finish/surface_samples.hpp"
#include "paths/finish/zone_machining.hpp"

#include <vector>

namespace drom::paths {

// What a zone looks like from its samples: its PCA plane, mean slope and mean steepest azimuth.
struct ZoneShape {
  PcaPlane plane;
  double mean_slope = 0, steepest_azimuth = 0;
  int samples = 0;
};
std::vector<ZoneShape> describe_zones(const SurfaceSamples& samples, const Zones& zones);

struct FinishingPlan {
  std::vector<ZoneMachining> zones;  // in machining order (each may run reversed)
  double move_time = 0;              // between zones: retract, traverse, (reorient,) plunge
  int moves = 0;
  double pass_time() const;
  double link_time() const;
  double retract_time() const;  // inside zones
  double pass_length() const;
  double link_length() const;
  int pass_count() const;
  // Contact points where the tool cuts into the surface beside the pass (curved model; PlanePass).
  int gouging_contacts() const;
  double time() const { return pass_time() + link_time() + retract_time() + move_time; }
  double length() const { return pass_length() + link_length(); }
};

// One setup per zone (zones.count() of them). In the machine accounting the zones are ordered by
// nearest next start (a zone may run reversed) and the moves between them are timed; in the seed's
// they keep their numbering and the moves cost nothing.
FinishingPlan plan_finishing(const MachiningMesh& mesh, const Zones& zones, const std::vector<ZoneSetup>& setups, const FinishingSettings& settings);

}  // namespace drom::paths
