#include "paths/copy/cloud_finishing.hpp"
#include "paths/cutter/stepover.hpp"

#include "paths/copy/tool_drop.hpp"
#include "support/input_error.hpp"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <sstream>
#include <stdexcept>

namespace drom::paths {

namespace {

constexpr double kInfinity = std::numeric_limits<double>::infinity();

// A flat end mill's level-ground step: the diameter less a 10 % overlap, a common shop rule (a flat
// bottom leaves nothing on level ground whatever the overlap).
constexpr double kFlatOverlap = 0.1;

struct Node {
  double x = 0, y = 0;
  Drop drop;
  bool inside = false;
  bool on_scan = false;  // the cutter rests on a scanned point (not on the part's side, the base or a fixture)
  bool cuttable() const { return inside && on_scan; }
  Eigen::Vector3d tip() const { return {x, y, drop.tip}; }
};

struct Row {
  double y = 0;
  std::vector<Node> nodes;  // the base grid's, in X order
};

// The tool dropped on a coarse grid over the area, and the step each of its rows allows.
struct Preview {
  double x0 = 0, y0 = 0, g = 1;
  int nx = 0, ny = 0;
  std::vector<double> row_step;
};

}  // namespace

double level_ground_spacing(const Tool& cutter, double scallop) {
  if (is_flat(cutter)) return 2 * cutter.radius * (1 - kFlatOverlap);
  return level_ground_stepover(cutter, scallop);
}

double transverse_spacing(const Tool& cutter, double scallop, const Eigen::Vector3d& normal, double concave_curvature) {
  const double cross = std::hypot(normal.y(), normal.z());
  // cos of the slope across the passes (1 where the normal lies in the XZ plane).
  const double cross_cos = cross > 0 ? std::abs(normal.z()) / cross : 1.0;
  if (is_flat(cutter)) {
    const double m = std::abs(normal.z()) > 0 ? std::abs(normal.y() / normal.z()) : kInfinity;
    return m > 0 ? scallop / m : kInfinity;
  }
  double along_surface = 0;
  if (cutter.kind == ToolKind::ball) {
    along_surface = flat_stepover(scallop, cutter.radius) / std::sqrt(1 + cutter.radius * std::max(0.0, concave_curvature));
  } else {
    const double slope = std::acos(std::clamp(std::abs(normal.z()), 0.0, 1.0));
    const double horizontal = std::hypot(normal.x(), normal.y());
    const double alpha = horizontal > 0 ? std::atan2(std::abs(normal.y()), std::abs(normal.x())) : 0.0;
    along_surface = std::min(flat_stepover(scallop, effective_radius(cutter, slope, alpha)), level_ground_stepover(cutter, scallop));
  }
  return along_surface * cross_cos;
}

double traverse_height(const geometry::CloudBins& bins, const ToolAssembly& tool, const Eigen::Vector2d& a, const Eigen::Vector2d& b, double clearance) {
  // Samples at most half a cutter radius apart, each widened by half the spacing: any position between
  // two samples lies within that of one of them, so the widened cylinders cover the traverse.
  const double length = (b - a).norm();
  const double spacing = std::max(1e-3, std::min(tool.cutter.radius / 2, 1.0));
  const int n = std::max(1, static_cast<int>(std::ceil(length / spacing)));
  const double widen = 0.5 * length / n + 1e-9;
  double top = -kInfinity;
  for (int i = 0; i <= n; ++i) {
    const Eigen::Vector2d p = a + (b - a) * (static_cast<double>(i) / n);
    top = std::max(top, bins.max_z_within(p.x(), p.y(), std::max(tool.cutter.radius, tool.shank()) + widen));
    if (tool.has_holder()) top = std::max(top, bins.max_z_within(p.x(), p.y(), tool.holder_reach() + widen) - tool.gauge_length);
  }
  return std::isfinite(top) ? top + clearance : clearance;
}

namespace {

// A move the chord tests could not resolve further (noise finer than the tolerance), counted.
struct Unresolved {
  long long count = 0;
  double worst = 0;
};

// A run of consecutive cuttable nodes of one pass, with the nodes the chord tests inserted.
struct Segment {
  std::vector<Node> nodes;
  // Per node k > 0: the height the move from node k - 1 goes round the corner at, or NaN when it
  // goes straight.
  std::vector<double> round_at;
  long long inserted = 0;
  Unresolved unresolved;
};

// Where the chord tests along a move go, and what error they may allow.
struct ChordTests {
  double spacing, tolerance;
};

// The planner's stages over one cloud, one area and one set of settings, with the settings' derived
// values computed once: place the passes, count what lies under them, cut them into segments refined
// by the chord test, join the segments into a program.
class CloudFinishingPlanner {
 public:
  CloudFinishingPlanner(const geometry::CloudBins& bins, const CloudArea& area, const CloudFinishingSettings& s)
      : bins_(bins), area_(area), s_(s), cutter_(s.tool.cutter), check_(s.check_spacing > 0 ? s.check_spacing : s.longitudinal_step / 2),
        level_step_(level_ground_spacing(cutter_, s.scallop)), smallest_(s.smallest_step > 0 ? s.smallest_step : 0.05 * level_step_),
        longest_link_(s.longest_link > 0 ? s.longest_link : std::max(2.0, 5 * level_step_)), steepest_(std::cos(s.steepest * std::numbers::pi / 180)),
        steepest_slope_(s.steepest < 90 ? std::tan(s.steepest * std::numbers::pi / 180) : kInfinity),
        shortest_(s.shortest_move > 0 ? s.shortest_move : s.longitudinal_step / 16), least_cos_(std::max(0.1, steepest_)),
        columns_(static_cast<int>(std::ceil((area.x_max() - area.x_min()) / s.longitudinal_step)) + 1) {}

  std::vector<Row> place_passes() const;
  void count_nodes(const std::vector<Row>& rows, CloudFinishing& out) const;
  std::vector<std::vector<Segment>> cut_segments(const std::vector<Row>& rows) const;
  void join_segments(const std::vector<Row>& rows, const std::vector<std::vector<Segment>>& segments, CloudFinishing& out) const;

 private:
  Row drop_row(double y) const;
  double fixed_step() const;
  Preview preview() const;
  double adaptive_step(const Preview& p, double y) const;
  ChordTests chord_tests(const Node& a, const Node& b) const;
  void refine(const Node& a, const Node& b, std::vector<Node>& into, long long& inserted, Unresolved& unresolved, int depth) const;
  double round_the_corner_at(const Node& a, const Node& n) const;
  bool link_is_safe(const Node& a, const Node& b) const;

  const geometry::CloudBins& bins_;
  const CloudArea& area_;
  const CloudFinishingSettings& s_;
  const Tool& cutter_;
  const double check_, level_step_, smallest_, longest_link_, steepest_, steepest_slope_, shortest_, least_cos_;
  const int columns_;  // the base grid along X
};

Row CloudFinishingPlanner::drop_row(double y) const {
  Row row;
  row.y = y;
  row.nodes.resize(static_cast<std::size_t>(columns_));
  tbb::parallel_for(0, columns_, [&](int k) {
    Node& n = row.nodes[static_cast<std::size_t>(k)];
    n.x = area_.x_min() + k * s_.longitudinal_step, n.y = y;
    n.inside = area_.contains(n.x, n.y);
    if (n.inside) {
      n.drop = drop_assembly(bins_, n.x, n.y, s_.tool);
      n.on_scan = n.drop.contact && (s_.scan_points < 0 || n.drop.point < s_.scan_points);
    }
  });
  return row;
}

// The step the fixed settings allow.
double CloudFinishingPlanner::fixed_step() const {
  if (s_.transverse == TransverseStep::fixed) return s_.transverse_step;
  const Eigen::Vector3d at_45(0, -std::sqrt(0.5), std::sqrt(0.5));
  return std::min(level_step_, transverse_spacing(cutter_, s_.scallop, at_45));
}

// The preview for the adaptive step: the tool dropped on a grid of half its radius over the area. Its
// slopes and its curvature across the passes are measured over that baseline, where the scan's spacing
// and noise (a few hundredths of a millimetre of dips and bumps in the dropped height, between points
// a few tenths apart) do not dominate them: measured between consecutive passes, they did, and the
// step fell to a fraction of what the surface needs (issue 45: a cap 5 times, a noise-free saddle 3.5
// times its length floor). The tip surface is the part offset by the ball: smooth at that scale but
// where the part has a concave crease, which no step keeps within the bound anyway.
Preview CloudFinishingPlanner::preview() const {
  Preview p;
  p.g = std::max(cutter_.radius / 2, s_.longitudinal_step);
  p.x0 = area_.x_min(), p.y0 = area_.y_min();
  p.nx = static_cast<int>(std::ceil((area_.x_max() - p.x0) / p.g)) + 1;
  p.ny = static_cast<int>(std::ceil((area_.y_max() - p.y0) / p.g)) + 1;
  const auto at = [&](int i, int j) { return static_cast<std::size_t>(j) * static_cast<std::size_t>(p.nx) + static_cast<std::size_t>(i); };
  std::vector<double> tip(static_cast<std::size_t>(p.nx) * static_cast<std::size_t>(p.ny), std::numeric_limits<double>::quiet_NaN());
  tbb::parallel_for(0, p.ny, [&](int j) {
    for (int i = 0; i < p.nx; ++i) {
      const double x = p.x0 + i * p.g, y = p.y0 + j * p.g;
      if (!area_.contains(x, y)) continue;
      const Drop d = drop_assembly(bins_, x, y, s_.tool);
      if (d.contact && !d.lifted && (s_.scan_points < 0 || d.point < s_.scan_points)) tip[at(i, j)] = d.tip;
    }
  });
  p.row_step.assign(static_cast<std::size_t>(p.ny), level_step_);
  const auto z = [&](int i, int j) { return i < 0 || j < 0 || i >= p.nx || j >= p.ny ? std::numeric_limits<double>::quiet_NaN() : tip[at(i, j)]; };
  // A derivative from the neighbours that exist: central, else one-sided; NaN with neither.
  const auto slope = [&](double before, double here, double after) {
    if (!std::isnan(before) && !std::isnan(after)) return (after - before) / (2 * p.g);
    if (!std::isnan(after)) return (after - here) / p.g;
    if (!std::isnan(before)) return (here - before) / p.g;
    return std::numeric_limits<double>::quiet_NaN();
  };
  for (int j = 0; j < p.ny; ++j)
    for (int i = 0; i < p.nx; ++i) {
      const double here = z(i, j);
      if (std::isnan(here)) continue;
      const double zx = slope(z(i - 1, j), here, z(i + 1, j)), zy = slope(z(i, j - 1), here, z(i, j + 1));
      const Eigen::Vector3d normal = Eigen::Vector3d(std::isnan(zx) ? 0.0 : -zx, std::isnan(zy) ? 0.0 : -zy, 1).normalized();
      if (normal.z() < steepest_) continue;
      double curvature = 0;
      if (cutter_.kind == ToolKind::ball && !std::isnan(z(i, j - 1)) && !std::isnan(z(i, j + 1))) {
        const double second = (z(i, j + 1) - 2 * here + z(i, j - 1)) / (p.g * p.g);
        curvature = second / std::pow(1 + zy * zy, 1.5);
      }
      double& row = p.row_step[static_cast<std::size_t>(j)];
      row = std::min(row, transverse_spacing(cutter_, s_.scallop, normal, curvature));
    }
  return p;
}

// The adaptive step from a pass at y: the least any preview row within a preview cell of the band the
// step spans allows.
double CloudFinishingPlanner::adaptive_step(const Preview& p, double y) const {
  const int j0 = std::max(0, static_cast<int>(std::floor((y - p.y0) / p.g)) - 1);
  const int j1 = std::min(p.ny - 1, static_cast<int>(std::ceil((y + level_step_ - p.y0) / p.g)) + 1);
  double step = level_step_;
  for (int j = j0; j <= j1; ++j) step = std::min(step, p.row_step[static_cast<std::size_t>(j)]);
  return step;
}

// Stage 1: the passes, placed one after the other.
std::vector<Row> CloudFinishingPlanner::place_passes() const {
  std::vector<Row> rows;
  const bool adaptive = s_.transverse == TransverseStep::adaptive;
  const Preview p = adaptive ? preview() : Preview{};
  double y = area_.y_min();
  rows.push_back(drop_row(y));
  while (y < area_.y_max() - 1e-9) {
    const double step = std::max(adaptive ? adaptive_step(p, y) : fixed_step(), smallest_);
    y = std::min(area_.y_max(), y + step);
    rows.push_back(drop_row(y));
  }
  return rows;
}

// Stage 2: what lies under the passes (gaps, lifted nodes, contacts too steep or beyond the bound),
// and the steps between them. No point under the whole area is the user's error.
void CloudFinishingPlanner::count_nodes(const std::vector<Row>& rows, CloudFinishing& out) const {
  for (const Row& row : rows)
    for (const Node& n : row.nodes) {
      if (!n.inside) continue;
      ++out.nodes;
      if (n.drop.lifted) ++out.lifted;
      if (!n.on_scan) {
        ++out.gaps;
        out.gap_nodes.emplace_back(n.x, n.y);
      } else if (n.drop.normal.z() < steepest_) {
        ++out.steeper;
      } else if (s_.transverse == TransverseStep::adaptive && !n.drop.lifted && transverse_spacing(cutter_, s_.scallop, n.drop.normal) < smallest_) {
        ++out.below_bound;
      }
    }
  if (out.nodes == out.gaps) {
    std::ostringstream m;
    m << "cloud finishing: no point of the cloud lies under the area asked for (x in [" << area_.x_min() << ", " << area_.x_max() << "], y in [" << area_.y_min()
      << ", " << area_.y_max() << "] of the drop frame, " << out.nodes << " nodes)";
    throw InputError(m.str());
  }
  out.passes = static_cast<int>(rows.size());
  for (std::size_t j = 0; j < rows.size(); ++j) {
    out.levels.push_back(rows[j].y);
    if (j == 0) continue;
    const double step = rows[j].y - rows[j - 1].y;
    out.smallest_step = j == 1 ? step : std::min(out.smallest_step, step);
    out.largest_step = std::max(out.largest_step, step);
    out.mean_step += step / static_cast<double>(rows.size() - 1);
  }
}

// Of Tu, the chord's dip below the dropped height takes 70 %; a quarter is the scan's: between
// points a ball dips below the surface they describe (drom copy completes the scan until that dip is
// at most Tu / 4, paths/copy/cloud_copy.cpp), and 5 % is left over, so the tool stands no deeper
// than Tu in the surface itself (issue 45's independent check).
//
// Over one of the points it touches, the cutter's dropped tip follows a sphere of the corner radius r;
// a straight move between two tests h apart sags below such a sphere by up to h^2 / (8 r cos^3 θ)
// vertically (θ its slope), which the tests do not see. The tests are placed so that this sag is at
// most an eighth of Tu, and the error they see is held to what is left of the 70 %. A flat end mill's
// envelope has steps, not a curvature: there, the tests keep the given spacing and the 70 %. The bound is not kept where it would ask for tests closer than half the shortest
// move, or on contacts steeper than `steepest` (θ is taken no steeper): there the tests still hold an
// eighth of Tu.
ChordTests CloudFinishingPlanner::chord_tests(const Node& a, const Node& b) const {
  const double r = cutter_.corner_radius, chord = 0.7 * s_.chord_tolerance;
  if (!(r > 0)) return {check_, chord};
  const double run = std::hypot(b.x - a.x, b.y - a.y);
  const double chord_cos = run > 0 ? run / std::hypot(run, b.drop.tip - a.drop.tip) : 1.0;
  const double c = std::clamp(std::min({chord_cos, std::abs(a.drop.normal.z()), std::abs(b.drop.normal.z())}), least_cos_, 1.0);
  const double spacing = std::min(check_, std::max(0.5 * shortest_, std::sqrt(r * s_.chord_tolerance * c * c * c)));
  return {spacing, std::max(0.125 * s_.chord_tolerance, chord - spacing * spacing / (8 * r * c * c * c))};
}

// Nodes inserted between a and b where the straight move strays from the dropped height by more than
// the chord tests allow, recursively at the worst test point.
void CloudFinishingPlanner::refine(const Node& a, const Node& b, std::vector<Node>& into, long long& inserted, Unresolved& unresolved, int depth) const {
  const double length = std::abs(b.x - a.x);
  const ChordTests tests = chord_tests(a, b);
  // At least the middle, however short the move, down to the shortest move allowed.
  const int samples = std::max(1, static_cast<int>(std::ceil(length / tests.spacing)) - 1);
  if (length > shortest_ && depth < 40) {
    // Below the dropped height (a gouge of the scan) the tests hold the move to their tolerance; above
    // it (stock left), to Tu and three deviations of the scan's noise: the dropped height rides the
    // noise's highest points, and a move asked to follow it closer than that chases the noise.
    const double above = s_.chord_tolerance + 3 * s_.noise;
    double worst = 0;
    Node worst_node;
    for (int i = 1; i <= samples; ++i) {
      const double t = static_cast<double>(i) / (samples + 1);
      Node m;
      m.x = a.x + t * (b.x - a.x), m.y = a.y, m.inside = true;
      m.drop = drop_assembly(bins_, m.x, m.y, s_.tool);
      if (!std::isfinite(m.drop.tip)) continue;  // nothing under the whole assembly: nothing to hit
      const double dip = m.drop.tip - (a.drop.tip + t * (b.drop.tip - a.drop.tip));
      const double excess = std::max(dip / tests.tolerance, -dip / above);
      if (excess > worst) worst = excess, worst_node = m;
    }
    if (worst > 1) {
      ++inserted;
      refine(a, worst_node, into, inserted, unresolved, depth + 1);
      into.push_back(worst_node);
      refine(worst_node, b, into, inserted, unresolved, depth + 1);
      return;
    }
  } else if (depth > 0) {
    // Too short to split again: how far it still strays (noise finer than the tolerance).
    Node m;
    m.x = 0.5 * (a.x + b.x), m.y = a.y, m.inside = true;
    m.drop = drop_assembly(bins_, m.x, m.y, s_.tool);
    if (std::isfinite(m.drop.tip)) {
      const double error = m.drop.tip - 0.5 * (a.drop.tip + b.drop.tip);  // a dip below the dropped height only
      if (error > s_.chord_tolerance) {
        ++unresolved.count;
        unresolved.worst = std::max(unresolved.worst, error);
      }
    }
  }
}

// A move the chord test could not resolve (a wall, a step in the dropped height: no node insertion
// makes the straight move clear it) goes round the corner instead: up at the lower end to the highest
// drop along it, across, down. NaN: the move goes straight.
double CloudFinishingPlanner::round_the_corner_at(const Node& a, const Node& n) const {
  double highest = std::max(a.drop.tip, n.drop.tip);
  // A move steeper than any contact the passes follow: on a steep flank the sag bound of the chord
  // tests no longer holds (the slope enters it cubed), and a move the chord test left as short as it
  // goes crosses a step in the dropped height (a wall, the cloud's edge seen from beside) that no
  // sample need fall on. Such a move is looked at closely, held to Tu, and one as short as it goes is
  // never fed straight.
  const double run = std::abs(n.x - a.x);
  const bool steep = std::abs(n.drop.tip - a.drop.tip) > run * steepest_slope_;
  bool straight = !(steep && run <= shortest_ * (1 + 1e-9));
  // A move the chord tests could not split further may still dip (issue 45: 951 such moves on a cap,
  // the worst 4.99 mm): it is held to Tu like a steep one, never fed straight through the dip.
  const bool shortest = run <= shortest_ * (1 + 1e-9);
  // Any other move the chord tests resolved: it goes straight (the whole-tool path check judges every
  // posted move afterwards, and refuses the program if one went too deep).
  if (!steep && !shortest) return std::numeric_limits<double>::quiet_NaN();
  const int samples = 16;
  const double allowance = 0.7 * s_.chord_tolerance;
  for (int i = 1; i < samples; ++i) {
    const double t = static_cast<double>(i) / samples;
    const double d = drop_assembly(bins_, a.x + t * (n.x - a.x), a.y + t * (n.y - a.y), s_.tool).tip;
    highest = std::max(highest, d);
    if (d > a.drop.tip + t * (n.drop.tip - a.drop.tip) + allowance) straight = false;
  }
  return straight ? std::numeric_limits<double>::quiet_NaN() : highest;
}

// Stage 3: each pass cut into segments of consecutive cuttable nodes, nodes inserted where a move
// strays from the dropped height by more than Tu (in parallel over the passes).
std::vector<std::vector<Segment>> CloudFinishingPlanner::cut_segments(const std::vector<Row>& rows) const {
  std::vector<std::vector<Segment>> segments(rows.size());
  tbb::parallel_for(std::size_t(0), rows.size(), [&](std::size_t j) {
    const bool reverse = s_.zigzag && j % 2 == 1;
    std::vector<Node> ordered = rows[j].nodes;
    if (reverse) std::reverse(ordered.begin(), ordered.end());
    Segment current;
    const auto close = [&] {
      if (!current.nodes.empty()) {
        current.round_at.assign(current.nodes.size(), std::numeric_limits<double>::quiet_NaN());
        for (std::size_t k = 1; k < current.nodes.size(); ++k) current.round_at[k] = round_the_corner_at(current.nodes[k - 1], current.nodes[k]);
        segments[j].push_back(std::move(current));
      }
      current = Segment();
    };
    for (const Node& n : ordered) {
      if (!n.cuttable()) {
        close();
        continue;
      }
      if (!current.nodes.empty()) {
        const Node a = current.nodes.back();
        refine(a, n, current.nodes, current.inserted, current.unresolved, 0);
      }
      current.nodes.push_back(n);
    }
    close();
  });
  return segments;
}

bool CloudFinishingPlanner::link_is_safe(const Node& a, const Node& b) const {
  const double length = std::hypot(b.x - a.x, b.y - a.y);
  if (length > longest_link_) return false;
  // A link steeper than any contact the passes follow crosses a step in the dropped height (the rim
  // of an overhang seen from a tilted packet: issue 45, 9 mm down over 0.065 mm between two passes),
  // where no test between its ends need fall on the step: it retracts instead.
  if (std::abs(b.drop.tip - a.drop.tip) > length * steepest_slope_) return false;
  const ChordTests tests = chord_tests(a, b);
  // At least the middle: a link shorter than the spacing is tested too.
  const int samples = std::max(2, static_cast<int>(std::ceil(length / tests.spacing)));
  for (int i = 1; i < samples; ++i) {
    const double t = static_cast<double>(i) / samples;
    const Drop d = drop_assembly(bins_, a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), s_.tool);
    if (d.tip > a.drop.tip + t * (b.drop.tip - a.drop.tip) + tests.tolerance) return false;
  }
  return true;
}

// Stage 4, the program: segments joined by feed links where the tool can stay on the cloud, by
// retracts (at a height that clears everything under the traverse) elsewhere.
void CloudFinishingPlanner::join_segments(const std::vector<Row>& rows, const std::vector<std::vector<Segment>>& segments, CloudFinishing& out) const {
  CloudPath& path = out.path;
  double top = -kInfinity;
  for (const Row& row : rows)
    for (const Node& n : row.nodes)
      if (n.cuttable()) top = std::max(top, n.drop.tip);
  const Node* last = nullptr;
  for (std::size_t j = 0; j < rows.size(); ++j)
    for (const Segment& segment : segments[j]) {
      out.inserted += segment.inserted;
      out.unresolved += segment.unresolved.count;
      out.unresolved_worst = std::max(out.unresolved_worst, segment.unresolved.worst);
      const Node& first = segment.nodes.front();
      if (!last) {
        const double start = traverse_height(bins_, s_.tool, Eigen::Vector2d(first.x, first.y), Eigen::Vector2d(first.x, first.y), s_.clearance);
        path.add({first.x, first.y, std::max(start, first.drop.tip + s_.approach)}, Motion::rapid);
        path.add({first.x, first.y, first.drop.tip + s_.approach}, Motion::rapid);
      } else if (link_is_safe(*last, first)) {
        ++out.links;
      } else {
        ++out.retracts;
        const double z = std::max({traverse_height(bins_, s_.tool, Eigen::Vector2d(last->x, last->y), Eigen::Vector2d(first.x, first.y), s_.clearance),
                                   last->drop.tip + s_.approach, first.drop.tip + s_.approach});
        path.add({last->x, last->y, z}, Motion::rapid);
        path.add({first.x, first.y, z}, Motion::rapid);
        path.add({first.x, first.y, first.drop.tip + s_.approach}, Motion::rapid);
      }
      const bool linked = last && path.motion.back() != Motion::rapid;
      for (std::size_t k = 0; k < segment.nodes.size(); ++k) {
        const Node& n = segment.nodes[k];
        if (k > 0 && !std::isnan(segment.round_at[k])) {
          const Node& a = segment.nodes[k - 1];
          const double highest = segment.round_at[k];
          ++out.stepped;
          if (highest > a.drop.tip) path.add({a.x, a.y, highest}, Motion::cut, static_cast<int>(j));
          if (highest > n.drop.tip) path.add({n.x, n.y, highest}, Motion::cut, static_cast<int>(j));
        }
        path.add(n.tip(), k == 0 && linked ? Motion::link : Motion::cut, static_cast<int>(j), n.drop.normal);
      }
      last = &segment.nodes.back();
    }
  if (last) path.add({last->x, last->y, std::max(top, last->drop.tip) + s_.clearance}, Motion::rapid);
}

}  // namespace

CloudFinishing plan_cloud_finishing(const geometry::CloudBins& bins, const CloudArea& area, const CloudFinishingSettings& s) {
  if (!(s.tool.cutter.radius > 0) || !(s.longitudinal_step > 0) || !(s.chord_tolerance > 0) || !(s.scallop > 0))
    throw std::invalid_argument("cloud finishing: the tool radius, longitudinal step, chord tolerance and scallop must be positive");
  if (s.transverse == TransverseStep::fixed && !(s.transverse_step > 0)) throw std::invalid_argument("cloud finishing: a fixed transverse step must be positive");
  if (area.empty()) throw InputError("cloud finishing: the area to finish is empty");
  const CloudFinishingPlanner planner(bins, area, s);
  CloudFinishing out;
  const std::vector<Row> rows = planner.place_passes();
  planner.count_nodes(rows, out);
  const std::vector<std::vector<Segment>> segments = planner.cut_segments(rows);
  planner.join_segments(rows, segments, out);
  return out;
}

}  // namespace drom::paths
