#include "paths/copy/cloud_path.hpp"

namespace drom::paths {

double CloudPath::cutting_length() const {
  double length = 0;
  for (std::size_t i = 1; i < tips.size(); ++i)
    if (motion[i] != Motion::rapid) length += (tips[i] - tips[i - 1]).norm();
  return length;
}

double CloudPath::rapid_length() const {
  double length = 0;
  for (std::size_t i = 1; i < tips.size(); ++i)
    if (motion[i] == Motion::rapid) length += (tips[i] - tips[i - 1]).norm();
  return length;
}

machine::ClProgram to_cl_program(const CloudPath& path, const Eigen::Matrix3d& q, double feed, const std::string& origin) {
  machine::ClProgram cl;
  cl.origin = origin;
  const Eigen::Vector3d axis = q.transpose() * Eigen::Vector3d::UnitZ();
  cl.points.reserve(path.size());
  for (std::size_t i = 0; i < path.size(); ++i) {
    machine::ClPoint p;
    p.pose.tip = q.transpose() * path.tips[i];
    p.pose.axis = axis;
    p.rapid = i == 0 || path.motion[i] == Motion::rapid;
    p.feed = p.rapid ? 0 : feed;
    p.line = static_cast<int>(i) + 1;
    cl.points.push_back(p);
  }
  return cl;
}

}  // namespace drom::paths
