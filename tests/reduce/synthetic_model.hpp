#pragma once
// A light model built from closed-form histories, for tests that need one without an offline run:
// a 200 x 100 target floor at z = 8 (10 x 5 Quad9 faces), one-way passes along x every 20 mm with a
// 12.5 mm flat end mill at 10 mm/s (rapid returns), four basis histories that grow with the machined
// area, and a smooth final-shape basis. Everything goes through the reduce/ classes that a real model
// uses (SurfaceMesh, SpaceTimeField from sampled histories).
#include "reduce/light_model.hpp"

#include <cmath>
#include <limits>

namespace drom::test {

// A flat ex x ey grid of Quad9 faces over [x0, x0 + lx] x [y0, y0 + ly] at height z.
inline reduce::SurfaceMesh quad9_grid(int ex, int ey, double x0, double y0, double lx, double ly, double z) {
  const int nx = 2 * ex + 1, ny = 2 * ey + 1;
  auto id = [&](int i, int j) { return j * nx + i; };
  Eigen::Matrix3Xd nodes(3, nx * ny);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) nodes.col(id(i, j)) = Eigen::Vector3d(x0 + lx * i / (nx - 1), y0 + ly * j / (ny - 1), z);
  std::vector<int> faces;
  for (int b = 0; b < ey; ++b)
    for (int a = 0; a < ex; ++a) {
      const int i = 2 * a, j = 2 * b;
      for (int v : {id(i, j), id(i + 2, j), id(i + 2, j + 2), id(i, j + 2), id(i + 1, j), id(i + 2, j + 1), id(i + 1, j + 2), id(i, j + 1), id(i + 1, j + 1)})
        faces.push_back(v);
    }
  return reduce::SurfaceMesh(nodes, faces, 9);
}

inline reduce::LightModel synthetic_model(double tool_radius = 12.5, reduce::ToolShape shape = reduce::ToolShape::Flat) {
  const double lx = 200, ly = 100, floor_z = 8;
  reduce::LightModel m;
  m.target = quad9_grid(10, 5, 0, 0, lx, ly, floor_z);
  const Eigen::Matrix3Xd nodes = m.target.nodes();
  const std::vector<int> faces = m.target.faces();

  // Passes along x at y = 10, 30, ..., 90: 20 s of cutting each, 5 s of rapid return and step.
  const int passes = 5;
  const double feed = 10, pass_time = lx / feed, cycle = pass_time + 5;
  std::vector<Eigen::Vector4d> path;
  for (int p = 0; p < passes; ++p) {
    const double y = 10 + 20 * p, t0 = p * cycle;
    path.emplace_back(0, y, floor_z, t0);
    path.emplace_back(lx, y, floor_z, t0 + pass_time);
    path.emplace_back(lx, y, floor_z + 5, t0 + pass_time + 0.5);
  }
  m.path.resize(static_cast<Eigen::Index>(path.size()), 4);
  for (std::size_t i = 0; i < path.size(); ++i) m.path.row(static_cast<Eigen::Index>(i)) = path[i].transpose();
  const double end = passes * cycle;

  // Cut time: the first pass within the tool radius, when the tool centre reaches x - sqrt(R^2 - dy^2).
  m.target_cut_time.resize(nodes.cols());
  for (Eigen::Index n = 0; n < nodes.cols(); ++n) {
    m.target_cut_time[n] = std::numeric_limits<double>::infinity();
    for (int p = 0; p < passes; ++p) {
      const double dy = nodes(1, n) - (10 + 20 * p);
      if (std::abs(dy) > tool_radius) continue;
      const double x_enter = std::max(0.0, nodes(0, n) - std::sqrt(tool_radius * tool_radius - dy * dy));
      m.target_cut_time[n] = p * cycle + x_enter / feed;
      break;
    }
  }

  // Histories sampled every 2.5 s, as an offline run's stations would be.
  const int stations = static_cast<int>(end / 2.5);
  Eigen::VectorXd times(stations);
  for (int s = 0; s < stations; ++s) times[s] = 2.5 * (s + 1);
  const int r = 4;
  for (int k = 0; k < r; ++k) {
    Eigen::MatrixXd H(nodes.cols(), stations);
    for (int s = 0; s < stations; ++s) {
      const double tau = times[s] / end;
      for (Eigen::Index n = 0; n < nodes.cols(); ++n) {
        const double x = nodes(0, n) / lx, y = nodes(1, n) / ly;
        const double u = k == 0 ? x * x * tau : k == 1 ? std::sin(M_PI * x) * std::sin(M_PI * y) * tau * tau : k == 2 ? (x - 0.5) * (y - 0.3) * std::sqrt(tau) : std::cos(2 * M_PI * x) * y * tau * (1 - 0.5 * tau);
        H(n, s) = 0.05 * u;
      }
    }
    m.histories.emplace_back(H, times, 1e-13, 0.0);
  }
  m.singular_values = Eigen::VectorXd::LinSpaced(6, 1.0, 0.01);
  m.right = Eigen::MatrixXd::Identity(6, r);
  m.prior_sd = Eigen::VectorXd::Ones(r);
  m.profile_scale = 50;
  m.shape_nodes = nodes;
  m.shape_faces = faces;
  m.shape_face_nodes = 9;
  m.final_basis.resize(3 * nodes.cols(), r);
  for (Eigen::Index n = 0; n < nodes.cols(); ++n)
    for (int c = 0; c < 3; ++c)
      for (int k = 0; k < r; ++k) {
        const double x = nodes(0, n) / lx, y = nodes(1, n) / ly;
        m.final_basis(3 * n + c, k) = (c == 2 ? 0.2 : 0.01) * std::cos((k + 1) * x + c) * std::sin((k + 2) * y + 0.3);
      }
  m.tool_shape = shape;
  m.tool_radius = tool_radius;
  m.pocket_depth = 2;
  m.case_toml = std::string("name = \"synthetic\"");
  m.database_hash = std::string("synthetic");
  return m;
}

// The stock's top for the synthetic model: 12 x 7 Quad9 faces over [-20, 220] x [-20, 120] at z = 10
// (the floor's footprint and a rim around it), histories of the same shapes as the floor's plus a
// twist of their own (the top is not the floor), and each node's cut time from the same passes.
inline void add_synthetic_top(reduce::LightModel& m) {
  m.top = quad9_grid(12, 7, -20, -20, 240, 140, 10);
  const Eigen::Matrix3Xd& nodes = m.top.nodes();
  // Cut: the first pass (a segment y = const, x from 0 to 200 at 10 mm/s) whose disc reaches the node.
  const double R = m.tool_radius, feed = 10, cycle = 25;
  m.top_cut_time.resize(nodes.cols());
  for (Eigen::Index n = 0; n < nodes.cols(); ++n) {
    m.top_cut_time[n] = std::numeric_limits<double>::infinity();
    for (int p = 0; p < 5; ++p) {
      const double dy = nodes(1, n) - (10 + 20 * p);
      if (std::abs(dy) > R) continue;
      const double half = std::sqrt(R * R - dy * dy);
      if (nodes(0, n) - half > 200 || nodes(0, n) + half < 0) continue;
      m.top_cut_time[n] = p * cycle + std::max(0.0, nodes(0, n) - half) / feed;
      break;
    }
  }
  const Eigen::VectorXd& times = m.histories.front().times();
  const double end = 5 * cycle;
  m.top_histories.clear();
  for (int k = 0; k < m.rank(); ++k) {
    Eigen::MatrixXd H(nodes.cols(), times.size() - 1);  // the stored instants after the leading start
    for (Eigen::Index s = 1; s < times.size(); ++s) {
      const double tau = times[s] / end;
      for (Eigen::Index n = 0; n < nodes.cols(); ++n) {
        const double x = nodes(0, n) / 200, y = nodes(1, n) / 100;
        const double u = k == 0 ? x * x * tau : k == 1 ? std::sin(M_PI * x) * std::sin(M_PI * y) * tau * tau : k == 2 ? (x - 0.5) * (y - 0.3) * std::sqrt(tau) : std::cos(2 * M_PI * x) * y * tau * (1 - 0.5 * tau);
        H(n, s - 1) = 0.05 * (u + 0.2 * (k + 1) * x * y * tau);
      }
    }
    m.top_histories.emplace_back(H, times.tail(times.size() - 1), 1e-13, 0.0);
  }
}

}  // namespace drom::test
