#include "tests/paths/copy/independent_checker.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <fstream>
#include <numbers>
#include <random>
#include <sstream>
#include <stdexcept>

namespace drom::tests::checker {

namespace {

constexpr double kBig = 1e9;
constexpr double kInf = std::numeric_limits<double>::infinity();

// A rotation whose third row is the axis: frame * axis = +Z.
Eigen::Matrix3d frame_of(const Eigen::Vector3d& axis) {
  const Eigen::Vector3d z = axis.normalized();
  const Eigen::Vector3d seed = std::abs(z.x()) < 0.9 ? Eigen::Vector3d::UnitX() : Eigen::Vector3d::UnitY();
  const Eigen::Vector3d x = (seed - seed.dot(z) * z).normalized();
  const Eigen::Vector3d y = z.cross(x);
  Eigen::Matrix3d m;
  m.row(0) = x, m.row(1) = y, m.row(2) = z;
  return m;
}

double segment_distance(const Eigen::Vector2d& p, const Eigen::Vector2d& a, const Eigen::Vector2d& b) {
  const Eigen::Vector2d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

double segment_distance3(const Eigen::Vector3d& p, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const Eigen::Vector3d ab = b - a;
  const double l2 = ab.squaredNorm();
  const double t = l2 > 0 ? std::clamp((p - a).dot(ab) / l2, 0.0, 1.0) : 0.0;
  return (p - (a + t * ab)).norm();
}

// Distance to the corner's quarter arc of centre c and radius r, from straight below c to straight
// beside it (angles -pi/2 to 0).
double quarter_arc_distance(const Eigen::Vector2d& p, const Eigen::Vector2d& c, double r) {
  const Eigen::Vector2d d = p - c;
  if (d.x() >= 0 && d.y() <= 0) return std::abs(d.norm() - r);
  return std::min((p - (c + Eigen::Vector2d(0, -r))).norm(), (p - (c + Eigen::Vector2d(r, 0))).norm());
}

// Points of a cloud in one frame, bucketed by the cells of their XY (cells of `cell` mm, blocks of
// 8 x 8 cells), each cell and block knowing its highest z.
class FrameGrid {
 public:
  FrameGrid(const std::vector<Eigen::Vector3d>& points, const Eigen::Matrix3d& frame, double cell) : cell_(cell) {
    local_.reserve(points.size());
    for (const auto& p : points) local_.push_back(frame * p);
    double lx = kInf, ly = kInf, hx = -kInf, hy = -kInf;
    for (const auto& p : local_) lx = std::min(lx, p.x()), ly = std::min(ly, p.y()), hx = std::max(hx, p.x()), hy = std::max(hy, p.y());
    if (local_.empty()) lx = ly = hx = hy = 0;
    x0_ = lx - cell, y0_ = ly - cell;
    nx_ = static_cast<int>((hx - x0_) / cell) + 2, ny_ = static_cast<int>((hy - y0_) / cell) + 2;
    bx_ = (nx_ + 7) / 8, by_ = (ny_ + 7) / 8;
    std::vector<int> count(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_) + 1, 0);
    for (const auto& p : local_) ++count[id(ix(p.x()), iy(p.y())) + 1];
    for (std::size_t c = 1; c < count.size(); ++c) count[c] += count[c - 1];
    start_ = count;
    order_.resize(local_.size());
    std::vector<int> fill(count.begin(), count.end() - 1);
    top_.assign(static_cast<std::size_t>(nx_) * static_cast<std::size_t>(ny_), -kInf);
    block_top_.assign(static_cast<std::size_t>(bx_) * static_cast<std::size_t>(by_), -kInf);
    for (std::size_t k = 0; k < local_.size(); ++k) {
      const int i = ix(local_[k].x()), j = iy(local_[k].y());
      order_[static_cast<std::size_t>(fill[id(i, j)]++)] = static_cast<int>(k);
      top_[id(i, j)] = std::max(top_[id(i, j)], local_[k].z());
      double& b = block_top_[static_cast<std::size_t>(j / 8) * static_cast<std::size_t>(bx_) + static_cast<std::size_t>(i / 8)];
      b = std::max(b, local_[k].z());
    }
  }
  const Eigen::Vector3d& local(int k) const { return local_[static_cast<std::size_t>(k)]; }
  // Every point within `radius` of the XY rectangle [x0, x1] x [y0, y1] whose cell stands above `floor`.
  template <class F>
  void visit(double x0, double x1, double y0, double y1, double radius, double floor, F&& f) const {
    const int i0 = std::max(0, ix(x0 - radius)), i1 = std::min(nx_ - 1, ix(x1 + radius));
    const int j0 = std::max(0, iy(y0 - radius)), j1 = std::min(ny_ - 1, iy(y1 + radius));
    if (i0 > i1 || j0 > j1) return;
    for (int bj = j0 / 8; bj <= j1 / 8; ++bj)
      for (int bi = i0 / 8; bi <= i1 / 8; ++bi) {
        if (block_top_[static_cast<std::size_t>(bj) * static_cast<std::size_t>(bx_) + static_cast<std::size_t>(bi)] < floor) continue;
        for (int j = std::max(j0, bj * 8); j <= std::min(j1, bj * 8 + 7); ++j)
          for (int i = std::max(i0, bi * 8); i <= std::min(i1, bi * 8 + 7); ++i) {
            const std::size_t c = id(i, j);
            if (top_[c] < floor) continue;
            for (int s = start_[c]; s < start_[c + 1]; ++s) f(order_[static_cast<std::size_t>(s)]);
          }
      }
  }

 private:
  int ix(double x) const { return std::clamp(static_cast<int>(std::floor((x - x0_) / cell_)), 0, nx_ - 1); }
  int iy(double y) const { return std::clamp(static_cast<int>(std::floor((y - y0_) / cell_)), 0, ny_ - 1); }
  std::size_t id(int i, int j) const { return static_cast<std::size_t>(j) * static_cast<std::size_t>(nx_) + static_cast<std::size_t>(i); }
  double cell_, x0_ = 0, y0_ = 0;
  int nx_ = 1, ny_ = 1, bx_ = 1, by_ = 1;
  std::vector<Eigen::Vector3d> local_;
  std::vector<int> start_, order_;
  std::vector<double> top_, block_top_;
};

// A 3D hash of points for ball queries (cells of `cell` mm).
class SpaceGrid {
 public:
  SpaceGrid(const std::vector<Eigen::Vector3d>& points, double cell) : points_(points), cell_(cell) {
    lo_ = Eigen::Vector3d::Constant(kInf);
    Eigen::Vector3d hi = Eigen::Vector3d::Constant(-kInf);
    for (const auto& p : points) lo_ = lo_.cwiseMin(p), hi = hi.cwiseMax(p);
    if (points.empty()) lo_.setZero(), hi.setZero();
    for (int a = 0; a < 3; ++a) n_[a] = static_cast<int>((hi[a] - lo_[a]) / cell) + 1;
    std::vector<int> count(static_cast<std::size_t>(n_[0]) * n_[1] * n_[2] + 1, 0);
    for (const auto& p : points) ++count[id(p) + 1];
    for (std::size_t c = 1; c < count.size(); ++c) count[c] += count[c - 1];
    start_ = count;
    order_.resize(points.size());
    std::vector<int> fill(count.begin(), count.end() - 1);
    for (std::size_t k = 0; k < points.size(); ++k) order_[static_cast<std::size_t>(fill[id(points[k])]++)] = static_cast<int>(k);
  }
  // Whether some point lies strictly within `radius` of c.
  bool any_within(const Eigen::Vector3d& c, double radius) const {
    int lo[3], hi[3];
    for (int a = 0; a < 3; ++a) {
      lo[a] = std::max(0, static_cast<int>(std::floor((c[a] - radius - lo_[a]) / cell_)));
      hi[a] = std::min(n_[a] - 1, static_cast<int>(std::floor((c[a] + radius - lo_[a]) / cell_)));
      if (lo[a] > hi[a]) return false;
    }
    for (int k = lo[2]; k <= hi[2]; ++k)
      for (int j = lo[1]; j <= hi[1]; ++j)
        for (int i = lo[0]; i <= hi[0]; ++i) {
          const std::size_t cell = (static_cast<std::size_t>(k) * n_[1] + j) * n_[0] + i;
          for (int s = start_[cell]; s < start_[cell + 1]; ++s)
            if ((points_[static_cast<std::size_t>(order_[static_cast<std::size_t>(s)])] - c).squaredNorm() < radius * radius) return true;
        }
    return false;
  }

 private:
  std::size_t id(const Eigen::Vector3d& p) const {
    int c[3];
    for (int a = 0; a < 3; ++a) c[a] = std::clamp(static_cast<int>(std::floor((p[a] - lo_[a]) / cell_)), 0, n_[a] - 1);
    return (static_cast<std::size_t>(c[2]) * n_[1] + c[1]) * n_[0] + c[0];
  }
  const std::vector<Eigen::Vector3d>& points_;
  double cell_;
  Eigen::Vector3d lo_;
  int n_[3] = {1, 1, 1};
  std::vector<int> start_, order_;
};

// The largest depth of the frame point q inside the tool swept from a to b (frame, axis +Z), by
// branch and bound over the move's parameter: depth is 1-Lipschitz in the tool's position, so an
// interval of length L (mm) cannot beat the larger end by more than L / 2.
double swept_depth(const ToolSolid& tool, const Eigen::Vector3d& q, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  const auto at = [&](double t) {
    const Eigen::Vector3d tip = a + t * (b - a);
    return tool.depth(std::hypot(q.x() - tip.x(), q.y() - tip.y()), q.z() - tip.z());
  };
  const double length = (b - a).norm();
  const int n = std::max(1, static_cast<int>(std::ceil(length / 0.05)));
  std::vector<double> d(static_cast<std::size_t>(n) + 1);
  double best = -kInf;
  for (int k = 0; k <= n; ++k) best = std::max(best, d[static_cast<std::size_t>(k)] = at(static_cast<double>(k) / n));
  struct Interval {
    double t0, t1, d0, d1;
  };
  std::vector<Interval> work;
  for (int k = 0; k < n; ++k) work.push_back({static_cast<double>(k) / n, static_cast<double>(k + 1) / n, d[static_cast<std::size_t>(k)], d[static_cast<std::size_t>(k) + 1]});
  while (!work.empty()) {
    const Interval w = work.back();
    work.pop_back();
    const double span = (w.t1 - w.t0) * length;
    // Only depths above 0 matter (inside), and only if they can beat what is found.
    if (std::max(w.d0, w.d1) + span / 2 <= std::max(best, 0.0) + 1e-7 || span < 1e-4) continue;
    const double tm = 0.5 * (w.t0 + w.t1), dm = at(tm);
    best = std::max(best, dm);
    work.push_back({w.t0, tm, w.d0, dm});
    work.push_back({tm, w.t1, dm, w.d1});
  }
  return best;
}

struct Deepest {
  double depth = 0;
  Eigen::Vector3d frame_point = Eigen::Vector3d::Zero();
};

// The deepest point of `grid` inside the tool swept from a to b.
Deepest deepest_in_move(const ToolSolid& tool, const FrameGrid& grid, const Eigen::Vector3d& a, const Eigen::Vector3d& b) {
  Deepest out;
  const ToolSpec& s = tool.spec();
  const double low = std::min(a.z(), b.z());
  const double near = std::max({s.radius, s.shank_radius > 0 ? s.shank_radius : s.radius});
  const double x0 = std::min(a.x(), b.x()), x1 = std::max(a.x(), b.x()), y0 = std::min(a.y(), b.y()), y1 = std::max(a.y(), b.y());
  const auto consider = [&](int k) {
    const Eigen::Vector3d& q = grid.local(k);
    const double rho = segment_distance(q.head<2>(), a.head<2>(), b.head<2>());
    if (q.z() - low < tool.lowest(rho)) return;  // never inside: below the tool's lowest point at its nearest
    const double d = swept_depth(tool, q, a, b);
    if (d > out.depth) out.depth = d, out.frame_point = q;
  };
  grid.visit(x0, x1, y0, y1, near, low, consider);
  if (s.gauge_length > 0 && s.holder_radius > near) {
    // The holder's ring beyond the shank, from its face up.
    grid.visit(x0, x1, y0, y1, s.holder_radius, low + s.gauge_length, [&](int k) {
      const Eigen::Vector3d& q = grid.local(k);
      if (segment_distance(q.head<2>(), a.head<2>(), b.head<2>()) <= near) return;  // seen above
      consider(k);
    });
  }
  return out;
}

}  // namespace

ClFile read_cl_csv(const std::filesystem::path& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error(file.string() + ": cannot open");
  ClFile cl;
  cl.origin = file.string();
  std::string line;
  int number = 0;
  std::vector<std::string> header;
  bool axis_set = false;
  while (std::getline(in, line)) {
    ++number;
    if (line.empty() || line[0] == '#') continue;
    std::vector<std::string> cells;
    std::stringstream ss(line);
    std::string cell;
    while (std::getline(ss, cell, ',')) cells.push_back(cell);
    if (header.empty()) {
      header = cells;
      const std::vector<std::string> want = {"x", "y", "z", "i", "j", "k", "feed"};
      if (header != want) throw std::runtime_error(cl.origin + ": line 1: expected the header x,y,z,i,j,k,feed");
      continue;
    }
    if (cells.size() != 7) throw std::runtime_error(cl.origin + ": line " + std::to_string(number) + ": expected 7 cells");
    double v[7];
    for (int c = 0; c < 7; ++c) {
      char* end = nullptr;
      v[c] = std::strtod(cells[static_cast<std::size_t>(c)].c_str(), &end);
      if (end == cells[static_cast<std::size_t>(c)].c_str() || !std::isfinite(v[c])) throw std::runtime_error(cl.origin + ": line " + std::to_string(number) + ": not a number");
    }
    const Eigen::Vector3d axis = Eigen::Vector3d(v[3], v[4], v[5]).normalized();
    if (!axis_set) cl.axis = axis, axis_set = true;
    else if ((axis - cl.axis).norm() > 1e-6) throw std::runtime_error(cl.origin + ": line " + std::to_string(number) + ": the axis changes (not a 3+2 file)");
    cl.tips.emplace_back(v[0], v[1], v[2]);
    cl.rapid.push_back(v[6] == 0);
  }
  return cl;
}

ToolSolid::ToolSolid(const ToolSpec& s) : s_(s) {
  if (s_.kind == ToolSpec::Kind::ball) s_.corner = s_.radius;
  if (s_.kind == ToolSpec::Kind::flat) s_.corner = 0;
  flutes_ = s_.flute_length > 0 ? s_.flute_length : 2 * s_.radius;
  shank_ = s_.shank_radius > 0 ? s_.shank_radius : s_.radius;
  gauge_ = s_.gauge_length > 0 && s_.holder_radius > 0 ? s_.gauge_length : kBig;
}

double ToolSolid::reach() const { return std::max({s_.radius, shank_, gauge_ < kBig ? s_.holder_radius : 0.0}); }

double ToolSolid::lowest(double rho) const {
  const double R = s_.radius, r = s_.corner, flat = R - r;
  if (rho <= flat) return 0;
  if (rho <= R) return r - std::sqrt(std::max(0.0, r * r - (rho - flat) * (rho - flat)));
  if (rho <= shank_) return flutes_;
  if (gauge_ < kBig && rho <= s_.holder_radius) return gauge_;
  return kInf;
}

bool ToolSolid::inside(double rho, double h) const {
  if (h < 0) return false;
  const double R = s_.radius, r = s_.corner;
  double section;
  if (h < r) section = R - r + std::sqrt(std::max(0.0, r * r - (r - h) * (r - h)));
  else if (h < flutes_) section = R;
  else if (h < gauge_) section = shank_;
  else section = s_.holder_radius;
  return rho < section;
}

double ToolSolid::boundary_distance(double rho, double h, bool cutter_only) const {
  const Eigen::Vector2d p(rho, h);
  const double R = s_.radius, r = s_.corner, flat = R - r;
  double d = kInf;
  if (flat > 0) d = std::min(d, segment_distance(p, {0, 0}, {flat, 0}));
  if (r > 0) d = std::min(d, quarter_arc_distance(p, {flat, r}, r));
  d = std::min(d, segment_distance(p, {R, r}, {R, flutes_}));
  if (cutter_only) return std::min(d, segment_distance(p, {0, flutes_}, {R, flutes_}));
  if (shank_ != R) d = std::min(d, segment_distance(p, {std::min(R, shank_), flutes_}, {std::max(R, shank_), flutes_}));
  d = std::min(d, segment_distance(p, {shank_, flutes_}, {shank_, std::min(gauge_, kBig)}));
  if (gauge_ < kBig) {
    d = std::min(d, segment_distance(p, {std::min(shank_, s_.holder_radius), gauge_}, {std::max(shank_, s_.holder_radius), gauge_}));
    d = std::min(d, segment_distance(p, {s_.holder_radius, gauge_}, {s_.holder_radius, kBig}));
  }
  return d;
}

bool ToolSolid::deeper_than(double rho, double h, double d) const {
  if (h < 0 || rho > reach() || !inside(rho, h)) return false;
  return boundary_distance(rho, h, false) > d;
}

double ToolSolid::depth(double rho, double h) const {
  // Far outside: a bound, not the distance (it never understates the depth, so the branch and bound
  // of swept_depth stays sound).
  if (h < 0) return h;
  if (rho > reach()) return reach() - rho;
  const double d = boundary_distance(rho, h, false);
  return inside(rho, h) ? d : -d;
}

double ToolSolid::cutter_distance(double rho, double h) const {
  const double d = boundary_distance(rho, h, true);
  const bool in = h >= 0 && h <= flutes_ && inside(rho, std::min(h, flutes_ - 1e-12)) && rho <= s_.radius;
  return in ? -d : d;
}

PathResult check_path(const ClFile& cl, const ToolSpec& spec, const std::vector<Eigen::Vector3d>& cloud, const std::vector<Eigen::Vector3d>& truth, double tolerance,
                      const std::vector<Eigen::Vector3d>& edge, double edge_radius, double edge_tolerance) {
  PathResult out;
  out.origin = cl.origin;
  out.axis = cl.axis;
  const Eigen::Matrix3d frame = frame_of(cl.axis);
  const ToolSolid tool(spec);
  // The true points split: away from the scan's open edge, and near it.
  std::vector<Eigen::Vector3d> away, near_edge;
  if (edge.empty() || !(edge_radius > 0)) {
    away = truth;
  } else {
    const SpaceGrid edges(edge, std::max(0.5, edge_radius));
    for (const auto& p : truth) (edges.any_within(p, edge_radius) ? near_edge : away).push_back(p);
  }
  const FrameGrid cloud_grid(cloud, frame, 1.0), truth_grid(away, frame, 1.0), edge_grid(near_edge, frame, 1.0);
  std::vector<Eigen::Vector3d> tips;
  for (const auto& t : cl.tips) tips.push_back(frame * t);
  for (std::size_t i = 1; i < tips.size(); ++i) {
    ++out.positions;
    const double allowed = cl.rapid[i] ? 1e-6 : tolerance + 1e-6;
    // A rapid leaving a cut starts where the cut left the tool, up to Tu deep (judged with the cut):
    // it is judged from where it has moved Tu on, so a retract straight out of the contact passes and
    // a rapid that stays in the material does not.
    Eigen::Vector3d start = tips[i - 1];
    const double length = (tips[i] - start).norm();
    if (cl.rapid[i] && i > 1 && !cl.rapid[i - 1] && length > 0) start += (tips[i] - start) * std::min(1.0, tolerance / length);
    const Deepest c = deepest_in_move(tool, cloud_grid, start, tips[i]);
    const Deepest t = deepest_in_move(tool, truth_grid, start, tips[i]);
    const Deepest e = near_edge.empty() ? Deepest{} : deepest_in_move(tool, edge_grid, start, tips[i]);
    if (e.depth > (cl.rapid[i] ? 1e-6 : edge_tolerance + 1e-6)) ++out.over_edge;
    if (e.depth > out.deepest_at_edge) out.deepest_at_edge = e.depth, out.worst_edge_part = frame.transpose() * e.frame_point;
    if ((c.depth > allowed || t.depth > allowed) && out.first_over.empty()) {
      char text[256];
      const Eigen::Vector3d a = cl.tips[i - 1], b = cl.tips[i];
      std::snprintf(text, sizeof text, "line %zu, %s from (%.3f, %.3f, %.3f) to (%.3f, %.3f, %.3f): %.4f into the scan, %.4f into the truth", i + 2,
                    cl.rapid[i] ? "rapid" : "feed", a.x(), a.y(), a.z(), b.x(), b.y(), b.z(), c.depth, t.depth);
      out.first_over = text;
    }
    if (c.depth > allowed) ++out.over_cloud;
    if (t.depth > allowed) ++out.over_truth;
    if (c.depth > out.deepest_cloud) out.deepest_cloud = c.depth, out.worst_cloud_frame = c.frame_point, out.worst_cloud_part = frame.transpose() * c.frame_point;
    if (t.depth > out.deepest_truth) out.deepest_truth = t.depth, out.worst_truth_frame = t.frame_point, out.worst_truth_part = frame.transpose() * t.frame_point;
  }
  return out;
}

namespace {

// The directions the checker tries: tilt 0 to max_tilt by 10 degrees, around by 15.
std::vector<Eigen::Vector3d> checker_directions(double max_tilt) {
  std::vector<Eigen::Vector3d> d = {Eigen::Vector3d::UnitZ()};
  for (double tilt = 10; tilt <= max_tilt + 1e-9; tilt += 10)
    for (double around = 0; around < 360 - 1e-9; around += 15) {
      const double t = tilt * std::numbers::pi / 180, a = around * std::numbers::pi / 180;
      d.emplace_back(std::sin(t) * std::cos(a), std::sin(t) * std::sin(a), std::cos(t));
    }
  return d;
}

// The visibility of each sampled point along each direction: the ball touching it along its normal
// fits (no solid point nearer its centre than R - graze), the direction within the window, and the
// assembly above the ball's centre clear of the solid (the base included) by the graze.
struct Visibility {
  std::vector<Eigen::Vector3d> directions;
  std::vector<int> samples;                       // indices into scanned
  std::vector<std::vector<std::uint64_t>> bits;   // per direction
  std::vector<char> any;                          // per sample: some direction
};

Visibility visibility(const std::vector<Eigen::Vector3d>& scanned, const std::vector<Eigen::Vector3d>& normals, const std::vector<Eigen::Vector3d>& solid,
                      const CoverageSettings& s, bool stop_at_first) {
  Visibility v;
  std::mt19937 rng(77);
  std::vector<int> all(scanned.size());
  for (std::size_t k = 0; k < all.size(); ++k) all[k] = static_cast<int>(k);
  std::shuffle(all.begin(), all.end(), rng);
  if (!s.unsure.empty() && s.unsure_radius > 0) {
    const SpaceGrid unsure(s.unsure, std::max(0.5, s.unsure_radius));
    all.erase(std::remove_if(all.begin(), all.end(), [&](int k) { return unsure.any_within(scanned[static_cast<std::size_t>(k)], s.unsure_radius); }), all.end());
  }
  all.resize(std::min<std::size_t>(all.size(), static_cast<std::size_t>(s.samples)));
  v.samples = all;
  const double R = s.tool.radius;
  const SpaceGrid space(solid, std::max(0.5, R / 2));
  std::vector<char> fits(all.size());
  for (std::size_t k = 0; k < all.size(); ++k) {
    const Eigen::Vector3d& q = scanned[static_cast<std::size_t>(all[k])];
    fits[k] = !space.any_within(q + R * normals[static_cast<std::size_t>(all[k])], R - s.graze);
  }
  v.directions = checker_directions(s.max_tilt);
  const std::size_t words = (all.size() + 63) / 64;
  v.bits.assign(v.directions.size(), std::vector<std::uint64_t>(words, 0));
  v.any.assign(all.size(), 0);
  const ToolSolid tool(s.tool);
  const double cos_window = std::cos(s.window * std::numbers::pi / 180);
  for (std::size_t j = 0; j < v.directions.size(); ++j) {
    const Eigen::Vector3d& d = v.directions[j];
    const Eigen::Matrix3d frame = frame_of(d);
    std::vector<int> todo;
    for (std::size_t k = 0; k < all.size(); ++k)
      if (fits[k] && d.dot(normals[static_cast<std::size_t>(all[k])]) >= cos_window - 1e-12 && !(stop_at_first && v.any[k])) todo.push_back(static_cast<int>(k));
    if (todo.empty()) continue;
    const FrameGrid grid(solid, frame, 1.0);
    for (const int k : todo) {
      const Eigen::Vector3d q = scanned[static_cast<std::size_t>(all[static_cast<std::size_t>(k)])];
      const Eigen::Vector3d centre = frame * (q + R * normals[static_cast<std::size_t>(all[static_cast<std::size_t>(k)])]);
      const Eigen::Vector3d tip = centre - Eigen::Vector3d(0, 0, R);
      bool clear = true;
      // Above the ball's centre: the cutter's cylinder and the shank near the axis; the holder, wider,
      // from its face up.
      const auto test = [&](int p) {
        if (!clear) return;
        const Eigen::Vector3d& x = grid.local(p);
        const double h = x.z() - tip.z();
        if (h <= R) return;
        const double dx = x.x() - tip.x(), dy = x.y() - tip.y();
        if (tool.deeper_than(std::sqrt(dx * dx + dy * dy), h, s.graze)) clear = false;
      };
      const double near = std::max(R, s.tool.shank_radius);
      grid.visit(tip.x(), tip.x(), tip.y(), tip.y(), near, centre.z(), test);
      if (clear && s.tool.gauge_length > 0 && s.tool.holder_radius > near) grid.visit(tip.x(), tip.x(), tip.y(), tip.y(), s.tool.holder_radius, tip.z() + s.tool.gauge_length, test);
      if (clear) {
        v.bits[j][static_cast<std::size_t>(k) >> 6] |= std::uint64_t{1} << (k & 63);
        v.any[static_cast<std::size_t>(k)] = 1;
      }
    }
  }
  return v;
}

}  // namespace

CoverageResult check_coverage(const std::vector<ClFile>& finishing, const std::vector<Eigen::Vector3d>& scanned, const std::vector<Eigen::Vector3d>& normals,
                              const std::vector<Eigen::Vector3d>& solid, const CoverageSettings& s) {
  CoverageResult out;
  const Visibility v = visibility(scanned, normals, solid, s, true);
  out.sampled = static_cast<long long>(v.samples.size());
  const ToolSolid tool(s.tool);
  const double R = s.tool.radius;
  std::vector<double> residual(v.samples.size(), kInf);
  for (const ClFile& cl : finishing) {
    const Eigen::Matrix3d frame = frame_of(cl.axis);
    std::vector<Eigen::Vector3d> tips;
    for (const auto& t : cl.tips) tips.push_back(frame * t);
    // The moves that cut (or link on the part), bucketed by the cells their XY box covers.
    const double cell = 1.0;
    double lx = kInf, ly = kInf, hx = -kInf, hy = -kInf;
    for (const auto& t : tips) lx = std::min(lx, t.x()), ly = std::min(ly, t.y()), hx = std::max(hx, t.x()), hy = std::max(hy, t.y());
    if (tips.size() < 2) continue;
    const int nx = static_cast<int>((hx - lx) / cell) + 1, ny = static_cast<int>((hy - ly) / cell) + 1;
    std::vector<std::vector<int>> cells(static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny));
    for (std::size_t i = 1; i < tips.size(); ++i) {
      if (cl.rapid[i]) continue;
      const int i0 = static_cast<int>((std::min(tips[i - 1].x(), tips[i].x()) - lx) / cell), i1 = static_cast<int>((std::max(tips[i - 1].x(), tips[i].x()) - lx) / cell);
      const int j0 = static_cast<int>((std::min(tips[i - 1].y(), tips[i].y()) - ly) / cell), j1 = static_cast<int>((std::max(tips[i - 1].y(), tips[i].y()) - ly) / cell);
      for (int j = j0; j <= j1; ++j)
        for (int k = i0; k <= i1; ++k) cells[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(k)].push_back(static_cast<int>(i));
    }
    const double reach = R + s.reached + 1.0;
    for (std::size_t k = 0; k < v.samples.size(); ++k) {
      const Eigen::Vector3d q = frame * scanned[static_cast<std::size_t>(v.samples[k])];
      const int i0 = std::max(0, static_cast<int>((q.x() - reach - lx) / cell)), i1 = std::min(nx - 1, static_cast<int>((q.x() + reach - lx) / cell));
      const int j0 = std::max(0, static_cast<int>((q.y() - reach - ly) / cell)), j1 = std::min(ny - 1, static_cast<int>((q.y() + reach - ly) / cell));
      for (int j = j0; j <= j1; ++j)
        for (int c = i0; c <= i1; ++c)
          for (const int m : cells[static_cast<std::size_t>(j) * static_cast<std::size_t>(nx) + static_cast<std::size_t>(c)]) {
            const Eigen::Vector3d& a = tips[static_cast<std::size_t>(m) - 1];
            const Eigen::Vector3d& b = tips[static_cast<std::size_t>(m)];
            double r;
            if (s.tool.kind == ToolSpec::Kind::ball) {
              r = segment_distance3(q, a + Eigen::Vector3d(0, 0, R), b + Eigen::Vector3d(0, 0, R)) - R;
            } else {
              r = kInf;
              const int n = std::max(1, static_cast<int>(std::ceil((b - a).norm() / 0.01)));
              for (int t = 0; t <= n; ++t) {
                const Eigen::Vector3d tip = a + (b - a) * (static_cast<double>(t) / n);
                r = std::min(r, tool.cutter_distance(std::hypot(q.x() - tip.x(), q.y() - tip.y()), q.z() - tip.z()));
              }
            }
            residual[k] = std::min(residual[k], r);
          }
    }
  }
  std::vector<double> reached;
  for (std::size_t k = 0; k < v.samples.size(); ++k) {
    if (!v.any[k]) continue;
    ++out.machinable;
    if (residual[k] <= s.reached) {
      ++out.reached;
      reached.push_back(residual[k]);
    } else {
      out.missed.push_back(scanned[static_cast<std::size_t>(v.samples[k])]);
    }
  }
  out.coverage = out.machinable ? static_cast<double>(out.reached) / static_cast<double>(out.machinable) : 1.0;
  if (!reached.empty()) {
    std::sort(reached.begin(), reached.end());
    out.scallop = reached.back();
    out.scallop_p99 = reached[static_cast<std::size_t>(0.99 * static_cast<double>(reached.size() - 1))];
  }
  return out;
}

int fewest_directions(const std::vector<Eigen::Vector3d>& scanned, const std::vector<Eigen::Vector3d>& normals, const std::vector<Eigen::Vector3d>& solid,
                      const CoverageSettings& s, double share) {
  const Visibility v = visibility(scanned, normals, solid, s, false);
  const std::size_t words = v.any.empty() ? 0 : (v.any.size() + 63) / 64;
  const long long machinable = std::count(v.any.begin(), v.any.end(), 1);
  const long long target = static_cast<long long>(std::ceil(share * static_cast<double>(machinable) - 1e-9));
  const auto count = [&](std::initializer_list<std::size_t> dirs) {
    long long n = 0;
    for (std::size_t w = 0; w < words; ++w) {
      std::uint64_t u = 0;
      for (const std::size_t d : dirs) u |= v.bits[d][w];
      n += std::popcount(u);
    }
    return n;
  };
  const std::size_t m = v.directions.size();
  for (std::size_t a = 0; a < m; ++a)
    if (count({a}) >= target) return 1;
  for (std::size_t a = 0; a < m; ++a)
    for (std::size_t b = a + 1; b < m; ++b)
      if (count({a, b}) >= target) return 2;
  for (std::size_t a = 0; a < m; ++a)
    for (std::size_t b = a + 1; b < m; ++b)
      for (std::size_t c = b + 1; c < m; ++c)
        if (count({a, b, c}) >= target) return 3;
  return 4;
}

std::vector<Eigen::Vector3d> base_points(const Eigen::Vector2d& lo, const Eigen::Vector2d& hi, double top, double bottom, double step) {
  std::vector<Eigen::Vector3d> out;
  const int nx = std::max(1, static_cast<int>(std::ceil((hi.x() - lo.x()) / step))), ny = std::max(1, static_cast<int>(std::ceil((hi.y() - lo.y()) / step)));
  const int nz = std::max(1, static_cast<int>(std::ceil((top - bottom) / step)));
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) out.emplace_back(lo.x() + (hi.x() - lo.x()) * i / nx, lo.y() + (hi.y() - lo.y()) * j / ny, top);
  for (int k = 1; k <= nz; ++k) {
    const double z = top - (top - bottom) * k / nz;
    for (int i = 0; i <= nx; ++i) out.emplace_back(lo.x() + (hi.x() - lo.x()) * i / nx, lo.y(), z), out.emplace_back(lo.x() + (hi.x() - lo.x()) * i / nx, hi.y(), z);
    for (int j = 1; j < ny; ++j) out.emplace_back(lo.x(), lo.y() + (hi.y() - lo.y()) * j / ny, z), out.emplace_back(hi.x(), lo.y() + (hi.y() - lo.y()) * j / ny, z);
  }
  return out;
}

}  // namespace drom::tests::checker
