#pragma once
// Toolpaths: rapid, linear and circular (G17, optionally helical) moves of the tool tip, with the
// time along the path at the programmed feed, and tool stations.
#include <Eigen/Core>

#include <cstddef>
#include <vector>

namespace drom::levelset {

enum class MoveKind { Rapid, Linear, ArcCW, ArcCCW };

struct Move {
  MoveKind kind = MoveKind::Linear;
  Eigen::Vector3d start = Eigen::Vector3d::Zero(), end = Eigen::Vector3d::Zero();
  Eigen::Vector3d centre = Eigen::Vector3d::Zero();  // arcs: centre in the XY plane (its z is unused)
  double feed = 0;              // mm/s, cutting moves
  int source_line = 0;          // G-code line it came from (0: generated)
  int tool_length_offset = 0;   // active H number (G43 Hn), 0 when none; kept as data

  bool cutting() const { return kind != MoveKind::Rapid; }
  bool is_arc() const { return kind == MoveKind::ArcCW || kind == MoveKind::ArcCCW; }
  // Signed sweep angle of an arc (CCW positive; a full circle when start == end in XY).
  double sweep_angle() const;
  double length() const;
  Eigen::Vector3d point_at(double s) const;  // arc length s in [0, length()]
};

struct Toolpath {
  std::vector<Move> moves;
  double rapid_feed = 250;  // mm/s used to time rapid moves (15 m/min)
  double length() const;
};

// Points along a move: exact for lines; arcs subdivided so the chord error stays below tolerance.
std::vector<Eigen::Vector3d> move_polyline(const Move& move, double chord_tolerance);

// Time along the path at constant feed per move (rapids at rapid_feed); position <-> time.
class PathTimeline {
 public:
  explicit PathTimeline(const Toolpath& path);
  double duration() const { return start_time_.back(); }
  double length() const { return start_length_.back(); }
  std::size_t move_at_time(double t) const;
  Eigen::Vector3d position_at_time(double t) const;
  double length_at_time(double t) const;
  double time_at_length(double s) const;
  // Time at which the tool passes closest to x (cutting moves only; ties: the earliest).
  double time_of(const Eigen::Vector3d& x, double chord_tolerance = 0.01) const;
  double move_start_time(std::size_t m) const { return start_time_[m]; }
  double move_start_length(std::size_t m) const { return start_length_[m]; }

 private:
  const Toolpath& path_;
  std::vector<double> start_time_, start_length_;  // per move, plus one past the end
};

struct Station {
  double time = 0, path_length = 0;
  Eigen::Vector3d position = Eigen::Vector3d::Zero();
};

// Stations every `spacing` mm of cutting travel, and at the end of every cutting move sequence.
std::vector<Station> stations_by_spacing(const Toolpath& path, const PathTimeline& timeline, double spacing);
// A station at the end of every cutting move (the program's waypoints).
std::vector<Station> stations_at_waypoints(const Toolpath& path, const PathTimeline& timeline);

// The programmed path as a polyline of tool-tip positions and their program times (rows x, y, z, t;
// arcs within 0.01 mm), and whether each segment (i, i + 1) belongs to a cutting move (the last row:
// 0, past the end).
struct TimedWaypoints {
  Eigen::MatrixXd xyzt;
  std::vector<char> cutting;
};
TimedWaypoints timed_waypoints(const Toolpath& path, const PathTimeline& timeline);

// The cutting moves' polylines between path lengths s0 and s1 (what one station sweeps).
std::vector<std::vector<Eigen::Vector3d>> cutting_polylines(const Toolpath& path, const PathTimeline& timeline, double s0, double s1,
                                                            double chord_tolerance);

}  // namespace drom::levelset
