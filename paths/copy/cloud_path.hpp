#pragma once
// A 3-axis path computed on a cloud in one drop frame (the tool axis +Z), and its cutter-location data
// in the part frame: 3+2 machining, the axis fixed for the whole path (machine/cl_data.hpp). Every
// path planner on clouds (finishing, roughing) writes this, and the packets' outputs read it.
#include "machine/cl_data.hpp"

#include <Eigen/Core>

#include <string>
#include <vector>

namespace drom::paths {

enum class Motion : char {
  cut,      // at the feed, cutting (or riding at the dropped height)
  link,     // at the feed, between passes, over the cloud at a checked height
  rapid,    // a retract, traverse or approach above everything under it
};

struct CloudPath {
  std::vector<Eigen::Vector3d> tips;     // tool tip, drop frame (mm)
  std::vector<Eigen::Vector3d> normals;  // contact normal at cut points, drop frame; zero elsewhere
  std::vector<Motion> motion;            // how the tool reaches each point
  std::vector<int> pass;                 // the pass (or layer) each point belongs to; -1 for links and rapids
  void add(const Eigen::Vector3d& tip, Motion m, int pass_index = -1, const Eigen::Vector3d& normal = Eigen::Vector3d::Zero()) {
    tips.push_back(tip), motion.push_back(m), pass.push_back(pass_index), normals.push_back(normal);
  }
  std::size_t size() const { return tips.size(); }
  bool empty() const { return tips.empty(); }
  double cutting_length() const;  // along cut and link moves
  double rapid_length() const;
};

// The path in the part frame for a drop frame `q` (drop = q * part): tips q^T * tip, axis q^T * e_z;
// `feed` in mm/min for cuts and links.
machine::ClProgram to_cl_program(const CloudPath& path, const Eigen::Matrix3d& q, double feed, const std::string& origin);

}  // namespace drom::paths
