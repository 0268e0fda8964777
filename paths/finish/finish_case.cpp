#include "paths/finish/finish_case.hpp"

#include "machine/program_keys.hpp"
#include "paths/finish/surface_samples.hpp"
#include "support/input_error.hpp"
#include "support/toml_reader.hpp"

#include <cmath>
#include <numbers>
#include <sstream>

namespace drom::paths {

FinishCase load_finish_case(const std::filesystem::path& path, const std::vector<std::string>& overrides) {
  TomlReader r(read_input_file(path, "case file"), path.string(), overrides);
  FinishCase c;
  c.origin = path.string();
  c.name = r.text("name");
  c.description = r.text("description", "");
  c.surface = geometry::read_surface(r, "surface", path.parent_path());

  // [tool]
  const std::string kind = r.choice("tool.kind", {"ball", "torus", "auto"}, "auto");
  const double radius = r.real("tool.radius", Range::positive(), 5);
  const double corner = r.real("tool.corner_radius", Range::positive(), 2);
  if (kind != "ball" && corner >= radius) r.fail("tool.corner_radius", "must be below tool.radius");
  c.auto_tool = kind == "auto";
  c.ball = Tool{ToolKind::ball, radius, radius};
  c.torus = Tool{ToolKind::torus, radius, corner};
  c.settings.tool = kind == "ball" ? c.ball : c.torus;

  // [machine]: the limits along the path until machine/'s definitions replace them.
  Kinematics cutting, rapid;
  cutting.feed = r.real("machine.feed", Range::positive(), 5000) / 60;
  cutting.acceleration = rapid.acceleration = r.real("machine.acceleration", Range::positive(), 6000);
  cutting.jerk = rapid.jerk = r.real("machine.jerk", Range::positive(), 40000);
  rapid.feed = r.real("machine.rapid_feed", Range::positive(), 25000) / 60;
  c.settings.timer = MoveTimer(cutting, rapid);
  c.settings.clearance = r.real("machine.clearance", Range::positive(), 5);
  c.settings.approach = r.real("machine.approach", Range::non_negative(), 1);

  // [finish]
  const double smallest_radius = kind == "ball" ? radius : corner;
  c.settings.scallop = r.real("finish.scallop", Range::positive(), 0.01);
  if (c.settings.scallop >= smallest_radius) {
    std::ostringstream msg;
    msg << "must be below the tool's " << (kind == "ball" ? "radius" : "corner radius") << " (" << smallest_radius << " mm): a scallop that high is not a finish";
    r.fail("finish.scallop", msg.str());
  }
  const std::string stepover = r.choice("finish.stepover", {"curved", "flat", "seed"}, "curved");
  c.settings.stepover = stepover == "curved" ? StepoverModel::curved : stepover == "flat" ? StepoverModel::flat : StepoverModel::seed;
  c.settings.exact = r.choice("finish.variant", {"exact", "fast"}, "exact") == "exact";
  c.settings.chord_tolerance = r.real("finish.chord_tolerance", Range::positive(), 2e-4);
  if (c.settings.exact && c.settings.chord_tolerance >= 0.5 * c.settings.scallop) r.fail("finish.chord_tolerance", "must be below half of finish.scallop");
  // A CAM system runs its passes out past the edge of what it finishes; the seed's passes stop there.
  c.settings.run_out = r.real("finish.run_out", Range::non_negative(), c.settings.stepover == StepoverModel::seed ? 0.0 : 20 * radius);
  c.settings.zigzag = r.choice("finish.strategy", {"zigzag", "one_way"}, "zigzag") == "zigzag";
  c.settings.accounting = r.choice("finish.accounting", {"machine", "seed"}, "machine") == "machine" ? Accounting::machine : Accounting::seed;
  const std::string setup = r.choice("finish.setup", {"3-axis", "3+2", "heuristic"}, "3-axis");
  c.setup = setup == "3-axis" ? SetupMode::three_axis : setup == "3+2" ? SetupMode::three_plus_two : SetupMode::pca_heuristic;
  const bool turned = c.setup != SetupMode::three_axis || r.has("finish.orientation");
  c.machine_definition = r.text("machine.definition", std::string(turned ? "ucp710_like" : "vmc_3axis"));
  if (!std::filesystem::path(c.machine_definition).has_extension()) {
    // a shipped machine's name
  } else if (std::filesystem::path(c.machine_definition).is_relative()) {
    c.machine_definition = (path.parent_path() / c.machine_definition).string();
  }
  c.program = machine::read_program_keys(r, {});
  c.samples = static_cast<int>(r.integer("finish.samples", 4, 400, 80));
  c.mesh_step = r.real("finish.mesh_step", Range::open_closed(0, 10), 0.5);
  if (r.has("finish.orientation")) {
    const auto o = r.reals("finish.orientation", Range::closed(-180, 180));
    if (o.size() != 2) r.fail("finish.orientation", "expected [phi, psi] in degrees: the tool axis's angle to Z and its azimuth");
    constexpr double deg = std::numbers::pi / 180;
    c.orientation = Eigen::Vector2d(o[0] * deg, o[1] * deg);
    c.orientation_where = r.where("finish.orientation");
    const Eigen::Vector3d axis(std::sin(o[0] * deg) * std::cos(o[1] * deg), std::sin(o[0] * deg) * std::sin(o[1] * deg), std::cos(o[0] * deg));
    const SurfaceSamples s = sample_surface(c.surface.surface, c.surface.trim, c.samples, c.samples);
    for (int i = 0; i < s.size(); ++i)
      if (s.inside[static_cast<std::size_t>(i)] && s.normals[static_cast<std::size_t>(i)].dot(axis) < 0) {
        std::ostringstream msg;
        msg.precision(3);
        msg << "the tool axis (" << axis.transpose() << ") undercuts the surface at (u, v) = (" << s.features[static_cast<std::size_t>(i)](0) << ", "
            << s.features[static_cast<std::size_t>(i)](1) << "): its normal there points away from the tool";
        r.fail("finish.orientation", msg.str());
      }
  }

  // [zoning]
  c.optimize = r.boolean("zoning.optimize", true);
  {
    const auto k = r.reals("zoning.clusters", Range::closed(1, 50), std::vector<double>{2, 10});
    if (k.empty() || k.size() > 2 || k.front() != std::floor(k.front()) || k.back() != std::floor(k.back()) || k.back() < k.front())
      r.fail("zoning.clusters", "expected [K] or [K_min, K_max], whole numbers from 1 to 50");
    c.clusters_min = static_cast<int>(k.front());
    c.clusters_max = static_cast<int>(k.back());
  }
  c.algorithm = r.choice("zoning.algorithm", {"kmeans", "rpcl", "ward"}, "kmeans");
  if (c.optimize && c.algorithm != "kmeans") r.fail("zoning.algorithm", "the optimisation partitions with K-means (the seed's ch. 4); set zoning.optimize = false");
  const std::string metric = r.choice("zoning.metric", {"euclidean", "mahalanobis", "std_dev", "pca"}, "euclidean");
  c.clustering.metric = metric == "euclidean" ? Metric::euclidean : metric == "mahalanobis" ? Metric::mahalanobis : metric == "std_dev" ? Metric::std_dev : Metric::pca;
  c.clustering.pca_weight = r.choice("zoning.pca_weight", {"one_minus_ratio_squared", "ratio_squared"}, "one_minus_ratio_squared") == "ratio_squared"
                                ? PcaWeight::ratio_squared
                                : PcaWeight::one_minus_ratio_squared;
  c.rpcl_seed = static_cast<std::uint64_t>(r.integer("zoning.rpcl_seed", 0, 1000000000, 1));
  c.budget = r.real("zoning.budget", Range::positive(), 1000);
  c.surrogate = r.boolean("zoning.surrogate", true);
  r.finish();
  c.resolved_toml = r.resolved_text();
  return c;
}

}  // namespace drom::paths
