#pragma once
// `drom run --replan`: a finishing pass re-planned on the part as the model predicts it, not as drawn
// (issue 23, after Makki 2009's direct machining of points). The final part's upward faces, moved by
// the predicted final displacement, are sampled as a cloud; a ball is dropped on it along Z on a
// zigzag grid with chord-tested nodes (paths/copy/cloud_finishing.hpp). The path is then judged against
// the truth: at every cut node, the same tool dropped on the truth's surface (sampled the same way)
// gives the height it should have stood at; the difference is how far the path lies from the truth.
// The nominal path (the tool dropped on the drawn surface) is judged the same way: it is off by the
// distortion.
#include "online/predictor.hpp"
#include "paths/copy/cloud_finishing.hpp"

#include <Eigen/Core>

namespace drom::loop {

struct ReplanSettings {
  // mm between the cloud's points on each face; 0: sqrt(8 R Tu), so that the bumps a ball of radius R
  // rides between points (spacing^2 / 8R) stay within the chord tolerance Tu the finish refines to.
  double sample_spacing = 0;
  double min_up = 0.9;          // a face is finished from +Z when its normal's Z exceeds this
  paths::CloudFinishingSettings finishing;  // a ball D10, 1 mm along the passes, 2 µm scallop, by default
  ReplanSettings();
};

struct ReplannedFinish {
  long long cloud_points = 0, faces = 0;
  paths::CloudFinishing replanned;        // on the predicted surface (part frame: the drop frame is the part's)
  long long judged = 0;                   // cut nodes compared with the truth
  double max_error = 0, rms_error = 0;    // |replanned tip - tip on the truth|, mm
  double nominal_max_error = 0, nominal_rms_error = 0;  // the nominal path's (dropped on the drawn surface)
};

// `shape`: the predicted final shape (its nodes nominal, its displacement predicted); `truth`: the
// true final displacement at the same nodes.
ReplannedFinish replan_finish(const online::FinalShape& shape, const Eigen::Matrix3Xd& truth, const ReplanSettings& settings = {});

// The spacing the settings sample at (their own, or sqrt(8 R Tu)).
double sample_spacing(const ReplanSettings& settings);

// The final part's upward faces (outward normal within acos(min_up) of +Z) moved by `displacement`,
// sampled about every `spacing` mm (bilinear in each quad, linear in each triangle, from the corners
// of quadratic faces).
std::vector<Eigen::Vector3d> upward_surface_cloud(const online::FinalShape& shape, const Eigen::Matrix3Xd& displacement, double spacing, double min_up, long long* faces = nullptr);

}  // namespace drom::loop
