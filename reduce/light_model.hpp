#pragma once
// The light model (docs/design.md §5): what the online predictor needs, and nothing of the full-order
// databases. One HDF5 file, readable with h5py:
//   - the target machined surface (nominal nodes and faces) and the program time at which the tool
//     cut each of its nodes;
//   - U1: r basis histories of the target surface's vertical displacement, each kept as
//     sum_l a_l(node) b_l(t) (history_<k>_space, history_<k>_time over `history_times`);
//   - the POD's singular values and right vectors, its bounds and tolerances;
//   - U2 = B2 V_r D_r^-1 on the final part's surface (its nodes and faces);
//   - optionally U1_top = B1_top V_r D_r^-1 on the stock's top face (top_history_<k>_space / _time),
//     its nodes, faces and cut times;
//   - the prior on the coefficients alpha, the tool and the programmed path (tool tip, program time),
//   - the case (TOML) and the content hash of the database it came from.
// alpha relates to the case's unit profiles by alpha = D_r V_r^T c / profile_scale, with c the profile
// coefficients in MPa (one per direction and Legendre degree, the database's column order).
#include "reduce/space_time_field.hpp"
#include "reduce/surface_mesh.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

namespace drom::reduce {

enum class ToolShape { Flat, Ball };

struct LightModel {
  SurfaceMesh target;
  Eigen::VectorXd target_cut_time;            // per target node, program time (s); +inf if never cut
  std::vector<SpaceTimeField> histories;      // U1, r of them (unit 2-norm over stations x nodes)
  Eigen::VectorXd singular_values;            // all of the scaled B1 (mm)
  Eigen::MatrixXd right;                      // V_r: profiles x r
  double profile_scale = 1;                   // MPa per unit profile before the POD
  double tolerance = 0, history_tolerance = 0;  // mm: POD truncation, and all history compressions together
  double pod_max_bound = 0, pod_euclidean_bound = 0, history_bound = 0;  // mm
  Eigen::Matrix3Xd shape_nodes;               // the final part's surface (nominal positions)
  std::vector<int> shape_faces;
  int shape_face_nodes = 4;
  Eigen::MatrixXd final_basis;                // U2: (3 * shape nodes) x r, rows (node, component)
  Eigen::VectorXd prior_sd;                   // alpha ~ N(0, diag(prior_sd^2)), or
  Eigen::MatrixXd prior_covariance;           // r x r when the coefficients' plausible amplitudes differ (prior_sd its diagonal's root)
  Eigen::VectorXd prior_mean;                 // r: the expected alpha (the case's own profile); empty: 0
  ToolShape tool_shape = ToolShape::Flat;
  double tool_radius = 0;
  Eigen::MatrixXd path;                       // waypoints x 4: tool tip x, y, z and program time
  double pocket_depth = 0;                    // mm below the top: the target surface's depth
  // Optional: the stock's top face, read by the laser where the tool has not been. U1_top over the
  // same instants as U1 (held after each node's cut), its nodes' cut times, and its measured error.
  SurfaceMesh top;
  Eigen::VectorXd top_cut_time;
  std::vector<SpaceTimeField> top_histories;
  double top_history_bound = 0, top_error_bound = 0;  // mm: compression alone; truncation and compression
  std::string case_toml, database_hash;

  int rank() const { return static_cast<int>(histories.size()); }
  bool has_top() const { return !top_histories.empty(); }
  // The bound on the model's max error for any one database column (mm at profile_scale).
  double error_bound() const { return pod_max_bound + history_bound; }

  void write(const std::filesystem::path& path) const;  // atomic
  static LightModel read(const std::filesystem::path& path);  // throws InputError naming the file and dataset
};

}  // namespace drom::reduce
