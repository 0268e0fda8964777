#pragma once
// A nodal history on the target surface, w(node, t) at the offline stations, evaluated at any (x, y, t):
// the surface's shape functions in space, linear in program time, 0 at the program's start and held
// after the last station. In the closed loop it plays the real part: the truth run's displacement of
// the target surface (docs/design.md §6: the surface the tool cut then moves with it).
#include "reduce/space_time_field.hpp"
#include "reduce/surface_mesh.hpp"

#include <Eigen/Core>

#include <optional>

namespace drom::online {

class SurfaceHistory {
 public:
  SurfaceHistory() = default;
  // values: surface nodes x stations; times: the stations' program times (increasing, after start).
  SurfaceHistory(const reduce::SurfaceMesh& mesh, Eigen::MatrixXd values, Eigen::VectorXd times, double start = 0);

  const reduce::SurfaceMesh& mesh() const { return *mesh_; }
  // Nodal values at program time t. The last instant asked is cached: a profile's points, or a
  // step's tool position, all ask at one instant. Not thread safe.
  const Eigen::VectorXd& nodal(double t) const;
  double at(const reduce::SurfacePoint& p, double t) const;  // through the cache (nodal(t))
  // The same from the face's nodes only, leaving the cache alone: for many instants at few points.
  double at_instant(const reduce::SurfacePoint& p, double t) const;
  // ... where t's interval among times() is already known (reduce::locate_time's).
  double at_instant(const reduce::SurfacePoint& p, const reduce::TimeInterval& at) const;
  const Eigen::VectorXd& times() const { return times_; }  // the start, then the stations

 private:
  const reduce::SurfaceMesh* mesh_ = nullptr;
  Eigen::MatrixXd values_;  // nodes x (1 + stations), the first column 0 at start
  Eigen::VectorXd times_;   // start, then the stations
  mutable double cached_t_ = std::nan("");
  mutable Eigen::VectorXd cached_;
};

}  // namespace drom::online
