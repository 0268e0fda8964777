#include "levelset/toolpath.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace drom::levelset {

double Move::sweep_angle() const {
  const Eigen::Vector2d a = start.head<2>() - centre.head<2>(), b = end.head<2>() - centre.head<2>();
  double angle = std::atan2(a.x() * b.y() - a.y() * b.x(), a.dot(b));  // (-pi, pi]
  if (kind == MoveKind::ArcCCW && angle <= 1e-12) angle += 2 * M_PI;
  if (kind == MoveKind::ArcCW && angle >= -1e-12) angle -= 2 * M_PI;
  return angle;
}

double Move::length() const {
  if (!is_arc()) return (end - start).norm();
  const double radius = (start.head<2>() - centre.head<2>()).norm();
  return std::hypot(radius * std::abs(sweep_angle()), end.z() - start.z());
}

Eigen::Vector3d Move::point_at(double s) const {
  const double L = length();
  const double t = L > 0 ? std::clamp(s / L, 0.0, 1.0) : 0.0;
  if (!is_arc()) return start + t * (end - start);
  const Eigen::Vector2d a = start.head<2>() - centre.head<2>();
  const double angle = t * sweep_angle(), c = std::cos(angle), sn = std::sin(angle);
  return {centre.x() + c * a.x() - sn * a.y(), centre.y() + sn * a.x() + c * a.y(), start.z() + t * (end.z() - start.z())};
}

double Toolpath::length() const {
  double L = 0;
  for (const auto& m : moves) L += m.length();
  return L;
}

std::vector<Eigen::Vector3d> move_polyline(const Move& move, double chord_tolerance) {
  if (!move.is_arc()) return {move.start, move.end};
  const double radius = (move.start.head<2>() - move.centre.head<2>()).norm();
  const double sweep = std::abs(move.sweep_angle());
  // Sagitta r (1 - cos(dphi / 2)) <= tolerance.
  const double dphi = radius > chord_tolerance ? 2 * std::acos(1 - chord_tolerance / radius) : M_PI / 2;
  const int n = std::max(1, static_cast<int>(std::ceil(sweep / dphi)));
  std::vector<Eigen::Vector3d> points;
  const double L = move.length();
  for (int k = 0; k <= n; ++k) points.push_back(move.point_at(L * k / n));
  return points;
}

PathTimeline::PathTimeline(const Toolpath& path) : path_(path) {
  start_time_.push_back(0);
  start_length_.push_back(0);
  for (const auto& m : path.moves) {
    const double feed = m.cutting() ? m.feed : path.rapid_feed;
    start_time_.push_back(start_time_.back() + (feed > 0 ? m.length() / feed : 0));
    start_length_.push_back(start_length_.back() + m.length());
  }
}

std::size_t PathTimeline::move_at_time(double t) const {
  if (path_.moves.empty()) return 0;
  auto it = std::upper_bound(start_time_.begin(), start_time_.end(), t);
  const auto index = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, it - start_time_.begin() - 1));
  return std::min(index, path_.moves.size() - 1);
}

double PathTimeline::length_at_time(double t) const {
  if (path_.moves.empty()) return 0;
  const std::size_t m = move_at_time(t);
  const double dt = start_time_[m + 1] - start_time_[m];
  const double frac = dt > 0 ? std::clamp((t - start_time_[m]) / dt, 0.0, 1.0) : 1.0;
  return start_length_[m] + frac * path_.moves[m].length();
}

Eigen::Vector3d PathTimeline::position_at_time(double t) const {
  if (path_.moves.empty()) return Eigen::Vector3d::Zero();
  const std::size_t m = move_at_time(t);
  return path_.moves[m].point_at(length_at_time(t) - start_length_[m]);
}

double PathTimeline::time_at_length(double s) const {
  if (path_.moves.empty()) return 0;
  auto it = std::upper_bound(start_length_.begin(), start_length_.end(), s);
  auto m = static_cast<std::size_t>(std::max<std::ptrdiff_t>(0, it - start_length_.begin() - 1));
  m = std::min(m, path_.moves.size() - 1);
  const double len = start_length_[m + 1] - start_length_[m];
  const double frac = len > 0 ? std::clamp((s - start_length_[m]) / len, 0.0, 1.0) : 1.0;
  return start_time_[m] + frac * (start_time_[m + 1] - start_time_[m]);
}

double PathTimeline::time_of(const Eigen::Vector3d& x, double chord_tolerance) const {
  double best = std::numeric_limits<double>::infinity(), best_length = 0;
  for (std::size_t m = 0; m < path_.moves.size(); ++m) {
    const Move& move = path_.moves[m];
    if (!move.cutting()) continue;
    const auto pts = move_polyline(move, chord_tolerance);
    double along = 0;
    for (std::size_t k = 0; k + 1 < pts.size(); ++k) {
      const Eigen::Vector3d ab = pts[k + 1] - pts[k];
      const double len2 = ab.squaredNorm();
      const double t = len2 > 0 ? std::clamp((x - pts[k]).dot(ab) / len2, 0.0, 1.0) : 0.0;
      const double d = (pts[k] + t * ab - x).squaredNorm();
      if (d < best - 1e-18) {
        best = d;
        best_length = start_length_[m] + along + t * std::sqrt(len2);
      }
      along += std::sqrt(len2);
    }
  }
  return time_at_length(best_length);
}

std::vector<Station> stations_by_spacing(const Toolpath& path, const PathTimeline& timeline, double spacing) {
  std::vector<Station> stations;
  double since_last = 0;
  for (std::size_t m = 0; m < path.moves.size(); ++m) {
    const Move& move = path.moves[m];
    const double L = move.length();
    if (!move.cutting() || L <= 0) continue;
    double s = 0;
    while (since_last + (L - s) >= spacing - 1e-9) {
      s += spacing - since_last;
      since_last = 0;
      const double at = timeline.move_start_length(m) + s;
      stations.push_back({timeline.time_at_length(at), at, move.point_at(s)});
    }
    since_last += L - s;
    // Close the station at the end of a cutting sequence (before a rapid or the end of the program).
    const bool sequence_ends = m + 1 == path.moves.size() || !path.moves[m + 1].cutting();
    if (sequence_ends && since_last > 1e-9) {
      const double at = timeline.move_start_length(m + 1);
      stations.push_back({timeline.time_at_length(at), at, move.end});
      since_last = 0;
    }
  }
  return stations;
}

std::vector<Station> stations_at_waypoints(const Toolpath& path, const PathTimeline& timeline) {
  std::vector<Station> stations;
  for (std::size_t m = 0; m < path.moves.size(); ++m)
    if (path.moves[m].cutting() && path.moves[m].length() > 0) {
      const double at = timeline.move_start_length(m + 1);
      stations.push_back({timeline.time_at_length(at), at, path.moves[m].end});
    }
  return stations;
}

std::vector<std::vector<Eigen::Vector3d>> cutting_polylines(const Toolpath& path, const PathTimeline& timeline, double s0, double s1,
                                                            double chord_tolerance) {
  std::vector<std::vector<Eigen::Vector3d>> lines;
  for (std::size_t m = 0; m < path.moves.size(); ++m) {
    const Move& move = path.moves[m];
    const double a = timeline.move_start_length(m), b = timeline.move_start_length(m + 1);
    if (!move.cutting() || b <= s0 || a >= s1) continue;
    const double from = std::max(s0, a) - a, to = std::min(s1, b) - a;
    if (to - from <= 0) continue;
    std::vector<Eigen::Vector3d> pts{move.point_at(from)};
    if (move.is_arc()) {
      // Same chord rule as move_polyline, on the part of the arc this station sweeps.
      const double radius = (move.start.head<2>() - move.centre.head<2>()).norm();
      const double dphi = radius > chord_tolerance ? 2 * std::acos(1 - chord_tolerance / radius) : M_PI / 2;
      const double angle = std::abs(move.sweep_angle()) * (to - from) / (b - a);
      const int n = std::max(1, static_cast<int>(std::ceil(angle / dphi)));
      for (int k = 1; k < n; ++k) pts.push_back(move.point_at(from + (to - from) * k / n));
    }
    pts.push_back(move.point_at(to));
    if (!lines.empty() && (lines.back().back() - pts.front()).norm() < 1e-12)
      lines.back().insert(lines.back().end(), pts.begin() + 1, pts.end());
    else
      lines.push_back(std::move(pts));
  }
  return lines;
}

TimedWaypoints timed_waypoints(const Toolpath& path, const PathTimeline& timeline) {
  std::vector<Eigen::Vector4d> rows;
  TimedWaypoints out;
  for (std::size_t m = 0; m < path.moves.size(); ++m) {
    const auto& move = path.moves[m];
    const auto points = move_polyline(move, 0.01);
    double along = 0;
    for (std::size_t k = 0; k < points.size(); ++k) {
      if (k > 0) along += (points[k] - points[k - 1]).norm();
      if (k == 0 && !rows.empty()) continue;  // the previous move's end
      const double t = timeline.time_at_length(timeline.move_start_length(m) + std::min(along, move.length()));
      if (!rows.empty()) out.cutting.push_back(move.cutting());
      rows.emplace_back(points[k].x(), points[k].y(), points[k].z(), t);
    }
  }
  out.cutting.push_back(0);
  out.xyzt.resize(static_cast<Eigen::Index>(rows.size()), 4);
  for (std::size_t i = 0; i < rows.size(); ++i) out.xyzt.row(static_cast<Eigen::Index>(i)) = rows[i].transpose();
  return out;
}

}  // namespace drom::levelset
