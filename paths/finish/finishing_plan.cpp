#include "paths/finish/finishing_plan.hpp"

#include <algorithm>
#include <limits>

namespace drom::paths {

std::vector<ZoneShape> describe_zones(const SurfaceSamples& samples, const Zones& zones) {
  std::vector<std::vector<Eigen::Vector3d>> points(static_cast<std::size_t>(zones.count())), normals(points.size());
  for (int i = 0; i < samples.size(); ++i) {
    const int z = zones.zone[static_cast<std::size_t>(i)];
    if (z < 0) continue;
    points[static_cast<std::size_t>(z)].push_back(samples.points[static_cast<std::size_t>(i)]);
    normals[static_cast<std::size_t>(z)].push_back(samples.normals[static_cast<std::size_t>(i)]);
  }
  std::vector<ZoneShape> shapes(points.size());
  for (std::size_t z = 0; z < points.size(); ++z) {
    auto& s = shapes[z];
    s.samples = static_cast<int>(points[z].size());
    if (points[z].size() >= 3) s.plane = pca_plane(points[z]);
    s.mean_slope = mean_slope(normals[z]);
    s.steepest_azimuth = mean_steepest_azimuth(normals[z]);
  }
  return shapes;
}

namespace {

// One of the zones' figures summed over the plan.
double sum_over(const std::vector<ZoneMachining>& zones, double ZoneMachining::*figure) {
  double total = 0;
  for (const auto& z : zones) total += z.*figure;
  return total;
}

}  // namespace

double FinishingPlan::pass_time() const { return sum_over(zones, &ZoneMachining::pass_time); }
double FinishingPlan::link_time() const { return sum_over(zones, &ZoneMachining::link_time); }
double FinishingPlan::retract_time() const { return sum_over(zones, &ZoneMachining::retract_time); }
double FinishingPlan::pass_length() const { return sum_over(zones, &ZoneMachining::pass_length); }
double FinishingPlan::link_length() const { return sum_over(zones, &ZoneMachining::link_length); }
int FinishingPlan::gouging_contacts() const {
  int n = 0;
  for (const auto& z : zones) n += z.gouging_contacts();
  return n;
}

int FinishingPlan::pass_count() const {
  int n = 0;
  for (const auto& z : zones) n += static_cast<int>(z.passes.size());
  return n;
}

FinishingPlan plan_finishing(const MachiningMesh& mesh, const Zones& zones, const std::vector<ZoneSetup>& setups, const FinishingSettings& s) {
  FinishingPlan plan;
  std::vector<ZoneMachining> done;
  for (int z = 0; z < zones.count(); ++z) {
    auto zm = machine_zone(mesh, zone_cells(mesh, zones.zone, z), z, setups[static_cast<std::size_t>(z)], s);
    if (!zm.passes.empty()) done.push_back(std::move(zm));
  }
  if (s.accounting == Accounting::seed || done.empty()) {
    plan.zones = std::move(done);
    return plan;
  }
  // Nearest next start: from where the last zone ended, the closest zone entry (either end).
  std::vector<bool> used(done.size(), false);
  std::size_t current = 0;
  used[0] = true;
  plan.zones.push_back(std::move(done[0]));
  for (std::size_t step = 1; step < done.size(); ++step) {
    const Eigen::Vector3d here = plan.zones.back().end();
    double best = std::numeric_limits<double>::infinity();
    bool reverse = false;
    for (std::size_t k = 0; k < done.size(); ++k) {
      if (used[k]) continue;
      const double forward = (done[k].start() - here).norm(), backward = (done[k].end() - here).norm();
      if (forward < best) best = forward, current = k, reverse = false;
      if (backward < best) best = backward, current = k, reverse = true;
    }
    used[current] = true;
    if (reverse) reverse_zone(done[current]);
    const Eigen::Vector3d next = done[current].start();
    plan.move_time += s.timer.repositioning(here, next, std::max(here.z(), next.z()) + s.clearance, s.approach);
    ++plan.moves;
    plan.zones.push_back(std::move(done[current]));
  }
  return plan;
}

}  // namespace drom::paths
