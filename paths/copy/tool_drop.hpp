#pragma once
// The tool dropped on a cloud along its axis (inverse Z-buffer; Makki 2009 §2.3.3, the digest's §2.3
// general form): in a drop frame (the tool axis is +Z), the tool tip at node (x, y) stands at
//   z_tip = max over points p with rho_p <= R of  p_z - h(rho_p),   rho_p = |p_xy - (x, y)|,
// h the cutter's profile (tool_assembly.hpp). The maximising point is the contact; the contact
// normal (out of the material, towards the tool) is, from the contact, towards the ball's centre or
// the torus's tube centre, and the axis where the flat bottom touches. No point under the cutter is
// a gap: reported as such (contact = false), never a tool fallen to some floor.
//
// Three ways to the same number, bit for bit (tests/paths/copy/tool_drop_test.cpp): brute force over every
// point (the reference), the 2D bin grid (its pyramid of maxima searched best first: a block that
// cannot do better is not opened) and the k-d tree over XY (bench/clouds_bench.cpp times them).
#include "geometry/cloud_bins.hpp"
#include "geometry/cloud_kdtree.hpp"
#include "paths/cutter/tool_assembly.hpp"

#include <Eigen/Core>

#include <limits>
#include <span>
#include <vector>

namespace drom::paths {

struct Drop {
  bool contact = false;  // some point lies under the cutter; otherwise a gap
  double tip = -std::numeric_limits<double>::infinity();  // z of the tool tip, drop frame
  int point = -1;        // the contact point (cloud index); ties go to the lowest index
  Eigen::Vector3d normal = Eigen::Vector3d::UnitZ();  // contact normal, drop frame
  // Set by the assembly drop only: the shank or the holder, not the cutter, fixed the height (the
  // cutter then stands above the cloud without touching it there).
  bool lifted = false;
};

// The contact normal for the cutter at tip height `tip` over (x, y) touching point p.
Eigen::Vector3d contact_normal(const Tool& cutter, double x, double y, double tip, const Eigen::Vector3d& p);

// `points` in the drop frame.
Drop drop_brute_force(std::span<const Eigen::Vector3d> points, double x, double y, const Tool& cutter);
// `bins` built from the drop-frame points (their indices name the contact).
Drop drop_tool(const geometry::CloudBins& bins, double x, double y, const Tool& cutter);
// `xy_tree`: a 2D tree over the drop-frame points; `scratch` is reused between calls.
Drop drop_tool(const geometry::CloudKdTree& xy_tree, std::span<const Eigen::Vector3d> points, double x, double y, const Tool& cutter,
               std::vector<int>& scratch);

// The whole assembly: the cutter's drop, then raised if need be so that nothing within the shank's
// and the holder's radii stands above them.
Drop drop_assembly(const geometry::CloudBins& bins, double x, double y, const ToolAssembly& tool);

}  // namespace drom::paths
