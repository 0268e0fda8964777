#include "paths/finish/zone_machining.hpp"

#include <algorithm>
#include <cmath>

namespace drom::paths {

Eigen::Vector3d ZoneSetup::feed() const { return rotation.transpose() * Eigen::Vector3d(std::cos(azimuth), std::sin(azimuth), 0); }

ZoneMachining machine_zone(const MachiningMesh& mesh, const std::vector<int>& cells, int zone, const ZoneSetup& setup, const FinishingSettings& s) {
  ZoneMachining z;
  z.zone = zone;
  z.setup = setup;
  const PassSettings ps{.tool = s.tool,
                        .scallop = s.scallop,
                        .stepover = s.stepover,
                        .zigzag = s.zigzag,
                        .axis = setup.axis(),
                        .feed = setup.feed(),
                        .exact = s.exact,
                        .chord_tolerance = s.chord_tolerance,
                        .run_out = s.run_out};
  z.passes = plan_passes(mesh, cells, ps);
  const bool machine = s.accounting == Accounting::machine;
  z.timed_lines.reserve(z.passes.size());
  for (const auto& p : z.passes) {
    std::vector<Eigen::Vector3d> line(p.cc.size());
    for (std::size_t i = 0; i < p.cc.size(); ++i)
      line[i] = setup.to_machine(machine ? cutter_location(p.cc[i], p.normals[i], s.tool, ps.axis) : p.cc[i]);
    z.pass_time += s.timer.pass(line);
    z.pass_length += polyline_length(line);
    z.timed_lines.push_back(std::move(line));
  }
  z.retract_before.assign(z.passes.size(), false);
  for (std::size_t k = 1; k < z.passes.size(); ++k) {
    const Eigen::Vector3d &from = z.timed_lines[k - 1].back(), &to = z.timed_lines[k].front();
    const double d = (to - from).norm();
    const bool same_plane = z.passes[k].plane == z.passes[k - 1].plane;
    const double longest_link = std::max(2.0, s.link_steps * z.passes[k - 1].spacing);
    if (machine && (same_plane || d > longest_link)) {
      z.retract_time += s.timer.repositioning(from, to, std::max(from.z(), to.z()) + s.clearance, s.approach);
      ++z.retracts;
      z.retract_before[k] = true;
    } else {
      z.link_time += s.timer.link(from, to);
      z.link_length += d;
      ++z.links;
    }
  }
  return z;
}

int ZoneMachining::gouging_contacts() const {
  int n = 0;
  for (const auto& p : passes) n += p.gouging_contacts;
  return n;
}

void reverse_zone(ZoneMachining& z) {
  std::reverse(z.passes.begin(), z.passes.end());
  std::reverse(z.timed_lines.begin(), z.timed_lines.end());
  // The move into pass k becomes the move out of it: shift the flags by one.
  std::vector<bool> flags(z.retract_before.size(), false);
  for (std::size_t k = 1; k < flags.size(); ++k) flags[k] = z.retract_before[flags.size() - k];
  z.retract_before = flags;
  for (auto& p : z.passes) {
    std::reverse(p.cc.begin(), p.cc.end());
    std::reverse(p.normals.begin(), p.normals.end());
  }
  for (auto& l : z.timed_lines) std::reverse(l.begin(), l.end());
}

}  // namespace drom::paths
