#pragma once
// When the tool first cut a point of the target surface: the first program time at which the tool,
// its tip down at the point's altitude (within a tolerance), covers the point (horizontal distance
// <= the tool radius). The light model stores it per target node; the predictor needs it at every
// laser point, where a face's nodes may have been cut passes apart, so segments are bucketed on a
// grid and a query looks at the few that pass nearby.
#include <Eigen/Core>

#include <vector>

namespace drom::reduce {

// path: waypoints x, y, z, program time. `cutting` (optional, one flag per segment i -> i + 1): only
// those segments count; empty: every segment (moves above the floor are excluded by the altitude test).
double first_cover_time(const Eigen::MatrixXd& path, const std::vector<char>& cutting, const Eigen::Vector3d& point, double radius, double z_tolerance);

class CutTimeIndex {
 public:
  CutTimeIndex() = default;
  // Segments whose lowest end lies below `z_max` only (the rest never reach the floor).
  CutTimeIndex(const Eigen::MatrixXd& path, double radius, double z_tolerance, double z_max);
  // +inf where the tool never covers the point.
  double at(const Eigen::Vector3d& point) const;
  // Every stretch of program time during which the tool covers the point (entry, exit), in time
  // order, up to `until` (a stretch in progress then ends at `until`). The floor a flat tool leaves
  // is the lowest of its passes over the point, so the last cover is not always the one that counts.
  void covers(const Eigen::Vector3d& point, double until, std::vector<std::pair<double, double>>& out) const;

 private:
  Eigen::MatrixXd path_;
  double radius_ = 0, z_tolerance_ = 0;
  double x0_ = 0, y0_ = 0, cell_ = 1;
  int nx_ = 0, ny_ = 0;
  std::vector<std::vector<int>> buckets_;  // segment indices (sorted, so the first hit in time order wins ties)
};

}  // namespace drom::reduce
