#include "levelset/pocket_toolpath.hpp"

#include "paths/cutter/stepover.hpp"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace drom::levelset {

// On level ground the flat bottom leaves nothing; what is left between the two corner traces is the
// cutter's flat-ground scallop with the corner radius (paths/cutter/stepover.hpp), the corners' own
// height once they no longer overlap.
double scallop_height(const paths::ToolAssembly& tool, double stepover) {
  const double flat = 2 * (tool.cutter.radius - tool.cutter.corner_radius);
  if (stepover <= flat) return 0;
  return paths::flat_scallop(stepover - flat, tool.cutter.corner_radius);
}

double stepover_for_scallop(const paths::ToolAssembly& tool, double scallop) {
  const double r = tool.cutter.corner_radius;
  if (r <= 0) throw std::invalid_argument("a flat end mill leaves no scallop: set the stepover directly");
  if (!(scallop > 0 && scallop < r)) throw std::invalid_argument("scallop height must lie in (0, corner radius)");
  return paths::level_ground_stepover(tool.cutter, scallop);
}

double tool_tip_on_floor(const geometry::PartShape& shape, const paths::ToolAssembly& tool, double floor_t, double u, double v) {
  const Eigen::Vector3d centre = shape.from_parametric({u, v, floor_t});
  if (shape.kind() != geometry::PartShape::Kind::Panel) return centre.z();
  // The floor varies along x only (axis along y): scan the footprint's x-diameter, then refine.
  auto floor_z = [&](double x) {
    const Eigen::Vector3d p = shape.to_parametric({x, v, centre.z()});
    return shape.from_parametric({p.x(), v, floor_t}).z();
  };
  auto contact = [&](double rho) { return floor_z(centre.x() + rho) - tool.bottom_height(rho); };
  const int n = 64;
  double best_rho = 0, best = contact(0);
  for (int k = 0; k <= n; ++k) {
    const double rho = -tool.cutter.radius + 2 * tool.cutter.radius * k / n;
    if (const double z = contact(rho); z > best) best = z, best_rho = rho;
  }
  double lo = std::max(-tool.cutter.radius, best_rho - 2 * tool.cutter.radius / n), hi = std::min(tool.cutter.radius, best_rho + 2 * tool.cutter.radius / n);
  for (int it = 0; it < 60; ++it) {
    const double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
    if (contact(m1) < contact(m2)) lo = m1; else hi = m2;
  }
  return std::max(best, contact(0.5 * (lo + hi)));
}

std::vector<double> pass_positions(const PocketSpec& pocket, const paths::ToolAssembly& tool, double stepover) {
  const double first = pocket.y_min + tool.cutter.radius, last = pocket.y_min + pocket.length_y - tool.cutter.radius;
  if (last < first - 1e-9) throw std::invalid_argument("the pocket is narrower than the tool");
  std::vector<double> v{first};
  while (v.back() + stepover < last - 1e-9) v.push_back(v.back() + stepover);
  if (last - v.back() > 1e-9) v.push_back(last);  // the last pass follows the wall
  return v;
}

namespace {

class PathBuilder {
 public:
  PathBuilder(const geometry::PartShape& shape, const paths::ToolAssembly& tool, const PocketSpec& pocket, const PocketPathSpec& spec)
      : shape_(shape), tool_(tool), spec_(spec), floor_t_(shape.thickness() - pocket.depth), safe_z_(shape.thickness() + spec.clearance) {}

  Eigen::Vector3d floor_point(double u, double v) const {
    Eigen::Vector3d p = shape_.from_parametric({u, v, floor_t_});
    p.z() = tool_tip_on_floor(shape_, tool_, floor_t_, u, v);
    return p;
  }
  void rapid_to(const Eigen::Vector3d& p) { add(MoveKind::Rapid, p, 0); }
  void cut_to(const Eigen::Vector3d& p, double feed) { add(MoveKind::Linear, p, feed); }
  // Cuts along the floor from (u0, v0) to (u1, v1), subdividing where the floor is curved.
  void cut_along_floor(double u0, double v0, double u1, double v1) {
    int n = 1;
    if (shape_.kind() == geometry::PartShape::Kind::Panel && std::abs(u1 - u0) > 0) {
      const double radius = shape_.outer_radius() - shape_.thickness() + floor_t_;
      const double dphi = 2 * std::acos(1 - std::min(0.5, spec_.chord_tolerance / radius));
      n = std::max(1, static_cast<int>(std::ceil(std::abs(u1 - u0) / shape_.outer_radius() / dphi)));
    }
    for (int k = 1; k <= n; ++k) cut_to(floor_point(u0 + (u1 - u0) * k / n, v0 + (v1 - v0) * k / n), spec_.feed);
  }
  void plunge_at(double u, double v) {
    const Eigen::Vector3d bottom = floor_point(u, v);
    rapid_to({bottom.x(), bottom.y(), safe_z_});
    cut_to(bottom, spec_.plunge_feed);
  }
  void retract() { rapid_to({position_.x(), position_.y(), safe_z_}); }
  Toolpath finish() {
    Toolpath path;
    path.moves = std::move(moves_);
    return path;
  }
  void start_at(const Eigen::Vector3d& p) { position_ = p; }

 private:
  void add(MoveKind kind, const Eigen::Vector3d& p, double feed) {
    if ((p - position_).norm() < 1e-12) return;
    Move m;
    m.kind = kind;
    m.start = position_;
    m.end = p;
    m.feed = feed;
    moves_.push_back(m);
    position_ = p;
  }

  const geometry::PartShape& shape_;
  const paths::ToolAssembly& tool_;
  const PocketPathSpec& spec_;
  double floor_t_, safe_z_;
  Eigen::Vector3d position_ = Eigen::Vector3d::Zero();
  std::vector<Move> moves_;
};

}  // namespace

Toolpath pocket_toolpath(const geometry::PartShape& shape, const PocketSpec& pocket, const paths::ToolAssembly& tool, const PocketPathSpec& spec) {
  if (!(spec.stepover > 0)) throw std::invalid_argument("stepover must be positive");
  if (spec.stepover > 2 * tool.cutter.radius) throw std::invalid_argument("stepover exceeds the tool diameter: material would be left between passes");
  if (pocket.depth >= tool.flute_length) throw std::invalid_argument("pocket deeper than the tool's flutes");
  const double u0 = pocket.x_min + tool.cutter.radius, u1 = pocket.x_min + pocket.length_x - tool.cutter.radius;
  if (u1 < u0) throw std::invalid_argument("the pocket is shorter than the tool");
  PathBuilder b(shape, tool, pocket, spec);
  const auto first = b.floor_point(u0, pocket.y_min + tool.cutter.radius);
  b.start_at({first.x(), first.y(), shape.thickness() + spec.clearance});

  if (spec.strategy == PocketStrategy::OneWay || spec.strategy == PocketStrategy::Zigzag) {
    const auto passes = pass_positions(pocket, tool, spec.stepover);
    bool forward = true;
    for (std::size_t k = 0; k < passes.size(); ++k) {
      const double from = forward ? u0 : u1, to = forward ? u1 : u0;
      if (spec.strategy == PocketStrategy::OneWay || k == 0)
        b.plunge_at(from, passes[k]);
      else
        b.cut_along_floor(from, passes[k - 1], from, passes[k]);  // step over at depth
      b.cut_along_floor(from, passes[k], to, passes[k]);
      if (spec.strategy == PocketStrategy::OneWay) b.retract();
      else forward = !forward;
    }
    if (spec.strategy == PocketStrategy::Zigzag) b.retract();
    if (spec.finish_walls) {
      const double lo_v = passes.front(), hi_v = passes.back();
      b.plunge_at(u0, lo_v);
      b.cut_along_floor(u0, lo_v, u1, lo_v);
      b.cut_along_floor(u1, lo_v, u1, hi_v);
      b.cut_along_floor(u1, hi_v, u0, hi_v);
      b.cut_along_floor(u0, hi_v, u0, lo_v);
      b.retract();
    }
    return b.finish();
  }

  // Inward spiral: rectangular rings offset by the stepover, joined at depth.
  double lo_u = u0, hi_u = u1, lo_v = pocket.y_min + tool.cutter.radius, hi_v = pocket.y_min + pocket.length_y - tool.cutter.radius;
  if (hi_v < lo_v) throw std::invalid_argument("the pocket is narrower than the tool");
  b.plunge_at(lo_u, lo_v);
  while (true) {
    if (hi_u - lo_u < 1e-9 || hi_v - lo_v < 1e-9) {
      b.cut_along_floor(lo_u, lo_v, hi_u, hi_v);  // what is left is a line
      break;
    }
    b.cut_along_floor(lo_u, lo_v, hi_u, lo_v);
    b.cut_along_floor(hi_u, lo_v, hi_u, hi_v);
    b.cut_along_floor(hi_u, hi_v, lo_u, hi_v);
    b.cut_along_floor(lo_u, hi_v, lo_u, lo_v);
    const double step_u = std::min(spec.stepover, 0.5 * (hi_u - lo_u)), step_v = std::min(spec.stepover, 0.5 * (hi_v - lo_v));
    if (step_u < 1e-9 && step_v < 1e-9) break;
    b.cut_along_floor(lo_u, lo_v, lo_u + step_u, lo_v + step_v);
    lo_u += step_u, hi_u -= step_u, lo_v += step_v, hi_v -= step_v;
  }
  b.retract();
  return b.finish();
}

}  // namespace drom::levelset
