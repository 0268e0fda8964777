// Issue 23's benchmark, as JSON: a 1-million-point cloud (a femur-head-like ball on a neck, the
// seed's hip at its full density) copied with the seed's improved hip settings (4-§4: normals by
// spheres D7 launched along +-X, +-Y, +Z on a 0.5 mm grid; 216 directions, window [5, 85]; ball D6 on a
// D53 holder 40 mm out; finishing grid 0.2 mm; roughing flat D10, 3 x 3 x 2): the wall and CPU time of
// every stage, beside the seed's MATLAB minutes. Then the tool drop itself on the same cloud, the 2D
// bin grid against the k-d tree (nanoflann) and brute force, on the same nodes.
//   build/bench/clouds_bench [points, default 1000000]
#include "geometry/cloud_bins.hpp"
#include "geometry/cloud_kdtree.hpp"
#include "machine/machine_definition.hpp"
#include "paths/copy/cloud_copy.hpp"
#include "paths/copy/tool_drop.hpp"
#include "support/resources.hpp"
#include "tests/paths/copy/test_clouds.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>

int main(int argc, char** argv) {
  using namespace drom;
  const double wanted = argc > 1 ? std::atof(argv[1]) : 1e6;
  // The femur head's area is about 4 pi 20^2 + 2 pi 9 x 27.5: spacing for `wanted` points.
  const double area = 4 * std::numbers::pi * 400 + 2 * std::numbers::pi * 9 * 27.5;
  const auto part = tests::femur_head(20, 9, 45, std::sqrt(area / wanted));
  geometry::PointCloud cloud;
  cloud.origin = "femur head";
  cloud.points = part.points;
  // The seed's hip grid and hollow cone (drom's defaults are 10 x 10 degrees and [0, 85] since issue 45).
  const paths::CopySettings s = paths::read_copy_settings("", "<defaults>", {"visibility.theta_step=30", "visibility.cone=[5, 85]"});
  const machine::Machine m = machine::load_machine(s.machine);
  const machine::Kinematics kin(m);
  const auto start = std::chrono::steady_clock::now();
  const double cpu0 = process_cpu_seconds();
  const paths::CopyResult r = paths::copy_cloud(cloud, s, kin);
  const double wall = seconds_since(start), cpu = process_cpu_seconds() - cpu0;

  // The drop alone: 20 000 nodes over the ball's top, the same answers by three ways.
  const double cell = s.finishing.tool.cutter.radius / 2;
  auto t = std::chrono::steady_clock::now();
  const geometry::CloudBins bins(cloud.points, cell);
  const double bins_build = seconds_since(t);
  t = std::chrono::steady_clock::now();
  const geometry::CloudKdTree tree(cloud.points, 2);
  const double tree_build = seconds_since(t);
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-18, 18);
  std::vector<Eigen::Vector2d> nodes(20000);
  for (auto& n : nodes) n = {u(rng), u(rng)};
  // Tips kept per node (a gap's is -infinity): the two indexes must agree node by node.
  std::vector<double> by_bins(nodes.size()), by_tree(nodes.size());
  double sum_brute = 0;
  t = std::chrono::steady_clock::now();
  for (std::size_t k = 0; k < nodes.size(); ++k) by_bins[k] = paths::drop_tool(bins, nodes[k].x(), nodes[k].y(), s.finishing.tool.cutter).tip;
  const double bins_time = seconds_since(t);
  std::vector<int> scratch;
  t = std::chrono::steady_clock::now();
  for (std::size_t k = 0; k < nodes.size(); ++k) by_tree[k] = paths::drop_tool(tree, cloud.points, nodes[k].x(), nodes[k].y(), s.finishing.tool.cutter, scratch).tip;
  const double tree_time = seconds_since(t);
  t = std::chrono::steady_clock::now();
  const int brute_nodes = 200;
  for (int k = 0; k < brute_nodes; ++k) sum_brute += paths::drop_brute_force(cloud.points, nodes[static_cast<std::size_t>(k)].x(), nodes[static_cast<std::size_t>(k)].y(), s.finishing.tool.cutter).tip;
  const double brute_time = seconds_since(t) * static_cast<double>(nodes.size()) / brute_nodes;

  std::printf("{\n  \"cloud_points\": %zu,\n  \"points_with_normals\": %zu,\n  \"directions\": %zu,\n  \"packets\": %zu,\n  \"coverage\": %.4f,\n", r.cloud_points,
              r.row_points.size(), r.visibility.columns.size(), r.packets.directions.size(),
              static_cast<double>(r.packets.covered) / static_cast<double>(r.row_points.size()));
  long long finishing_points = 0;
  for (const auto& p : r.plans) finishing_points += static_cast<long long>(p.finish_op.path.size());
  std::printf("  \"finishing_path_points\": %lld,\n  \"stages\": [\n", finishing_points);
  // The seed's MATLAB minutes on a Core 2 Duo (Makki 2009, 4-§4.1, 4-§4.3; 4-§2.3, 4-§3.1 for the 175 k run).
  for (std::size_t k = 0; k < r.times.size(); ++k)
    std::printf("    {\"stage\": \"%s\", \"wall_s\": %.3f, \"cpu_s\": %.3f}%s\n", r.times[k].stage.c_str(), r.times[k].wall, r.times[k].cpu, k + 1 < r.times.size() ? "," : "");
  std::printf("  ],\n  \"total_wall_s\": %.3f,\n  \"total_cpu_s\": %.3f,\n  \"goal_s\": 10,\n  \"peak_memory_mb\": %.0f,\n", wall, cpu,
              static_cast<double>(peak_memory_bytes()) / 1048576.0);
  std::printf("  \"seed_minutes\": {\"normals\": 126, \"visibility\": 240, \"finishing\": 250},\n");
  std::printf("  \"drop\": {\"nodes\": %zu, \"bins_build_s\": %.3f, \"kdtree_build_s\": %.3f, \"bins_s\": %.4f, \"kdtree_s\": %.4f, \"brute_force_s_estimated\": %.2f, \"same_answer\": %s}\n}\n",
              nodes.size(), bins_build, tree_build, bins_time, tree_time, brute_time, by_bins == by_tree ? "true" : "false");
  return 0;
}
