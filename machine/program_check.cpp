#include "machine/program_check.hpp"

#include "machine/cl_data.hpp"
#include "machine/gcode_reader.hpp"
#include "machine/program_verdict.hpp"
#include "support/atomic_file.hpp"
#include "support/run_folder.hpp"
#include "support/input_error.hpp"
#include "support/png_plot.hpp"
#include "support/resources.hpp"
#include "support/summary.hpp"
#include "support/vtk_fields.hpp"

#include <cctype>
#include <chrono>
#include <fstream>
#include <regex>
#include <cmath>
#include <cstdio>
#include <numbers>

namespace drom::machine {

namespace fs = std::filesystem;

namespace {

struct Loaded {
  MachineProgram program;
  std::string reader;
  bool start_assumed = false;
  std::vector<JointPath::Violation> violations;  // from the inverse kinematics (CL input)
};

Loaded load(const ProgramCheckOptions& o, const Kinematics& kin) {
  Loaded l;
  if (is_cl_file(o.program)) {
    const ClProgram cl = read_cl_file(o.program);
    ClOnMachine on = cl_to_machine_program(cl, kin);
    for (auto& v : on.joints.violations) {
      v.what = o.program.string() + ":" + std::to_string(cl.points[v.pose].line) + ": " + v.what;
      l.violations.push_back(v);
    }
    l.program = std::move(on.program);
    l.reader = "cl";
    return l;
  }
  const NcProgram nc = read_program(o.program, o.read);
  l.program = to_machine_program(nc, kin.machine());
  l.reader = nc.reader;
  l.start_assumed = nc.start_assumed;
  return l;
}

std::string axis_label(const Machine& m, int j) { return std::string(1, m.axes[j].name); }

// A subroutine file: its first statement opens an O-word `sub` and its last closes it (`endsub`),
// comments, blank lines and '%' aside. It moves the machine only where a program calls it.
// A malformed comment is no subroutine file: the reader then names the line.
bool is_subroutine_file(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> statements;
  for (std::string raw; std::getline(in, raw);) {
    std::string line;
    try {
      for (char c : statement_of(raw, ""))
        if (!std::isspace(static_cast<unsigned char>(c))) line += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
    } catch (const InputError&) {
      return false;
    }
    if (!line.empty() && line != "%") statements.push_back(line);
  }
  static const std::regex opens(R"(^o(<[^>]*>|\d+)sub$)"), closes(R"(^o(<[^>]*>|\d+)endsub.*$)");
  return statements.size() >= 2 && std::regex_match(statements.front(), opens) && std::regex_match(statements.back(), closes);
}

nlohmann::json machine_summary(const Machine& m) {
  return {{"name", m.name}, {"origin", m.origin}, {"kinematics", chain_name(m.chain)}, {"rotary_axes", m.rotary_letters()},
          {"interpolation_cycle_s", m.interpolation_cycle}, {"junction", m.junction == JunctionMode::Blend ? "blend" : m.junction == JunctionMode::Smooth ? "smooth" : "exact_stop"},
          {"tool_length_mm", m.tool_length}};
}

// A program with no motion (a subroutine file, a tool-change demo) is a program, not bad input: it
// takes no time on the machine.
nlohmann::json report_no_motion(const ProgramCheckOptions& o, RunFolder& folder, const Machine& m, const std::string& reader, double read_s,
                                std::chrono::steady_clock::time_point start, const std::string& what = "the program ends without moving the machine") {
  nlohmann::json s;
  s["command"] = "machine";
  s["program"] = fs::absolute(o.program).string();
  s["reader"] = reader;
  s["no_motion"] = true;
  s["no_motion_reason"] = what;
  s["machine"] = machine_summary(m);
  s["blocks"] = 0;
  s["cycle_time_s"] = 0.0;
  s["programmed_time_s"] = 0.0;
  s["cutting_length_mm"] = 0.0;
  s["travel_violations"] = nlohmann::json::array();
  s["singularity_passages"] = nlohmann::json::array();
  s["timing_s"] = {{"read", read_s}, {"total", seconds_since(start)}};
  s["files"] = {"summary.json"};
  s["host"] = machine_info();
  write_summary(folder.staging(), s);
  folder.commit();
  return s;
}

}  // namespace

nlohmann::json check_program(const ProgramCheckOptions& o) {
  const auto start = std::chrono::steady_clock::now();
  const Machine m = load_machine(o.machine, o.machine_overrides);
  const Kinematics kin(m);
  if (!is_cl_file(o.program) && is_subroutine_file(o.program)) {
    RunFolder folder(o.out, {.resume = false, .reused = {}, .inputs = {o.program}});
    return report_no_motion(o, folder, m, "drom", seconds_since(start), start, "a subroutine file: its moves run where a program calls it");
  }
  Loaded loaded = load(o, kin);
  const MachineProgram& program = loaded.program;
  const double read_s = seconds_since(start);
  RunFolder folder(o.out, {.resume = false, .reused = {}, .inputs = {o.program}});  // before the prediction: an output folder that cannot be written is found now
  if (program.blocks.empty()) return report_no_motion(o, folder, m, loaded.reader, read_s, start);

  // Travel per block end, passages near the singular direction and the demand at the programmed
  // feed: the verdict drom gives every program it posts (CL input: the inverse kinematics' findings
  // stand for the strokes, with the CL file's lines).
  const ProgramVerdict verdict = scan_program(program, o.program.string(), kin);
  std::vector<JointPath::Violation> travel = loaded.violations;
  if (loaded.reader != "cl")
    for (const StrokeExcess& e : verdict.beyond_strokes) travel.push_back({e.block, e.joint, e.value, e.what});

  const auto t_predict = std::chrono::steady_clock::now();
  const FeedPrediction p = predict_feed(program, kin);
  const double predict_s = seconds_since(t_predict);

  const auto t_write = std::chrono::steady_clock::now();
  const fs::path& out = folder.staging();
  std::vector<std::string> files;
  const int nj = m.joint_count();
  auto programmed_feed = [&](std::size_t block) {
    const BlockPrediction& b = p.blocks[block];
    return b.programmed_duration > 0 && b.length > 0 ? 60 * b.length / b.programmed_duration : 0.0;
  };
  // Samples in time.
  const double period = o.sample_period > 0 ? o.sample_period : m.interpolation_cycle;
  const double dt = std::max(period, p.cycle_time / 200000);
  const long long samples = static_cast<long long>(std::floor(p.cycle_time / dt)) + 1;
  {
    std::string feed = "t_s,s,feed_per_min,programmed_feed_per_min,block,line,limit,limit_axis\n";
    std::string axes = "t_s";
    for (int j = 0; j < nj; ++j) {
      const std::string a = axis_label(m, j), u = m.axes[j].rotary ? "deg" : "mm";
      axes += "," + a + "_" + u + "," + a + "_" + u + "_s," + a + "_" + u + "_s2," + a + "_" + u + "_s3";
    }
    axes += "\n";
    PlotSeries predicted{"predicted feed", {}, {}, "-"}, programmed{"programmed feed", {}, {}, "--"};
    char buf[128];
    for (long long k = 0; k < samples; ++k) {
      const PathState st = p.at_time(std::min(p.cycle_time, static_cast<double>(k) * dt));
      const JointState js = p.joints_at(st);
      const BlockPrediction& b = p.blocks[st.block];
      const double fed = programmed_feed(st.block);
      std::snprintf(buf, sizeof buf, "%.6f,%.6f,%.3f,%.3f,%zu,%d,%s,%s\n", st.t, st.s, st.v * 60, fed, st.block, program.blocks[st.block].line,
                    feed_limit_name(b.limit), b.limit_axis >= 0 ? axis_label(m, b.limit_axis).c_str() : "");
      feed += buf;
      predicted.x.push_back(st.s);
      predicted.y.push_back(st.v * 60);
      programmed.x.push_back(st.s);
      programmed.y.push_back(fed > 0 ? fed : std::nan(""));
      std::snprintf(buf, sizeof buf, "%.6f", st.t);
      axes += buf;
      for (int j = 0; j < nj; ++j) {
        const double u = m.axes[j].rotary ? 180 / std::numbers::pi : 1.0;
        std::snprintf(buf, sizeof buf, ",%.6f,%.5f,%.4f,%.3f", js.position[j] * u, js.velocity[j] * u, js.acceleration[j] * u, js.jerk[j] * u);
        axes += buf;
      }
      axes += "\n";
    }
    write_file_atomically(out / "feed.csv", feed);
    write_file_atomically(out / "axes.csv", axes);
    files.insert(files.end(), {"feed.csv", "axes.csv"});
    PlotSpec spec;
    spec.title = o.program.filename().string() + " on " + m.name + ": the feed it reaches";
    spec.x_label = "path length (mm of tool tip in the part frame)";
    spec.y_label = "feed (mm/min)";
    spec.series = {programmed, predicted};
    if (write_png_plot(out / "feed.png", spec)) files.push_back("feed.png");
  }
  {
    std::string csv = "block,line,type,length,t_start_s,duration_s,programmed_duration_s,cap_per_min,cap_source,cap_axis,limit,limit_axis,"
                      "velocity_axis,acceleration_axis,jerk_axis,min_feed_per_min,max_feed_per_min\n";
    char buf[320];
    for (std::size_t i = 0; i < p.blocks.size(); ++i) {
      const BlockPrediction& b = p.blocks[i];
      auto name = [&](int j) { return j >= 0 ? axis_label(m, j) : std::string(); };
      static const char* kTypes[] = {"rapid", "linear", "arc", "dwell"};
      std::snprintf(buf, sizeof buf, "%zu,%d,%s,%.6f,%.6f,%.6f,%.6f,%.3f,%s,%s,%s,%s,%s,%s,%s,%.3f,%.3f\n", i, program.blocks[i].line,
                    kTypes[static_cast<int>(program.blocks[i].type)], b.length, b.t_start, b.duration, b.programmed_duration,
                    std::isfinite(b.cap) ? b.cap * 60 : -1.0, feed_limit_name(b.cap_source), name(b.cap_axis).c_str(), feed_limit_name(b.limit),
                    name(b.limit_axis).c_str(), name(b.limiting_axis[0]).c_str(), name(b.limiting_axis[1]).c_str(), name(b.limiting_axis[2]).c_str(),
                    b.min_speed * 60, b.max_speed * 60);
      csv += buf;
    }
    write_file_atomically(out / "blocks.csv", csv);
    files.push_back("blocks.csv");
  }
  {
    // The tool tip's path in the part frame, one polyline per block, coloured by what held the feed.
    Polylines pl;
    std::vector<Eigen::Vector3d> points;
    std::vector<double> speed, limit, axis, ratio, line, rapid;
    for (std::size_t i = 0; i < program.blocks.size(); ++i) {
      const MachineBlock& b = program.blocks[i];
      const BlockPrediction& bp = p.blocks[i];
      if (!(bp.length > 0)) continue;
      const int pieces = b.type == MoveType::Arc ? 16 : 1;
      std::vector<long long> ids;
      for (int k = 0; k <= pieces; ++k) {
        const double sigma = static_cast<double>(k) / pieces;
        ids.push_back(static_cast<long long>(points.size()));
        points.push_back(kin.forward(block_joints_at(b, sigma)).tip);
        speed.push_back(p.at_time(p.time_at(bp.s_start + sigma * bp.length)).v * 60);
      }
      pl.lines.push_back(ids);
      limit.push_back(static_cast<double>(bp.limit));
      axis.push_back(bp.limit_axis);
      ratio.push_back(bp.programmed_duration > 0 ? bp.programmed_duration / std::max(bp.duration, 1e-300) : 1.0);
      line.push_back(b.line);
      rapid.push_back(b.type == MoveType::Rapid);
    }
    pl.points.resize(3, static_cast<Eigen::Index>(points.size()));
    for (std::size_t k = 0; k < points.size(); ++k) pl.points.col(static_cast<Eigen::Index>(k)) = points[k];
    pl.fields.point_scalars = {{"feed_per_min", speed}};
    pl.fields.cell_scalars = {{"limit (0 feed, 1 velocity, 2 cycle, 3 acceleration, 4 jerk, 5 none)", limit},
                              {"limit_axis (joint index)", axis},
                              {"programmed / predicted time", ratio},
                              {"line", line},
                              {"rapid", rapid}};
    write_polylines_vtp(out / "saturation.vtp", pl);
    files.push_back("saturation.vtp");
  }

  nlohmann::json s;
  s["command"] = "machine";
  s["program"] = fs::absolute(o.program).string();
  s["reader"] = loaded.reader;
  s["start_assumed"] = loaded.start_assumed;
  s["no_motion"] = false;
  s["machine"] = machine_summary(m);
  s["blocks"] = program.blocks.size();
  s["cycle_time_s"] = p.cycle_time;
  s["programmed_time_s"] = p.programmed_time;
  s["cycle_time_over_programmed"] = p.programmed_time > 0 ? p.cycle_time / p.programmed_time : 0.0;
  s["cutting_length_mm"] = p.cutting_length;
  s["length_at_programmed_feed_mm"] = p.length_at_programmed_feed;
  s["share_of_cutting_length_at_programmed_feed"] = p.cutting_length > 0 ? p.length_at_programmed_feed / p.cutting_length : 0.0;
  nlohmann::json sat = nlohmann::json::object();
  for (int j = 0; j < nj; ++j)
    sat[axis_label(m, j)] = {{"velocity", p.saturated_length[j][0]}, {"acceleration", p.saturated_length[j][1]}, {"jerk", p.saturated_length[j][2]}};
  s["saturated_length_mm"] = sat;
  nlohmann::json by_limit = nlohmann::json::object();
  for (const BlockPrediction& b : p.blocks) {
    if (!(b.length > 0)) continue;
    const std::string key = std::string(feed_limit_name(b.limit)) + (b.limit_axis >= 0 ? ":" + axis_label(m, b.limit_axis) : "");
    by_limit[key] = by_limit.value(key, 0) + 1;
  }
  s["blocks_by_limit"] = by_limit;
  nlohmann::json tv = nlohmann::json::array();
  for (const auto& v : travel) tv.push_back({{"block", v.pose}, {"axis", v.joint >= 0 ? axis_label(m, v.joint) : "orientation"}, {"what", v.what}});
  s["travel_violations"] = tv;
  s["travel_violation_count"] = loaded.reader == "cl" ? travel.size() : verdict.beyond_stroke_count;
  nlohmann::json sp = nlohmann::json::array();
  for (const auto& q : verdict.singular_passages) sp.push_back({{"line", q.line}, {"distance_deg", q.distance * 180 / std::numbers::pi}});
  s["singularity_passages"] = sp;
  s["demand_at_programmed_feed"] = verdict.demand_json();
  s["slows_down"] = verdict.slows_down();
  s["planner"] = {{"zero_acceleration_anchors", p.anchors}, {"passes", p.iterations}};
  s["timing_s"] = {{"read", read_s}, {"predict", predict_s}, {"write", seconds_since(t_write)}, {"total", seconds_since(start)}};
  s["files"] = files;
  s["host"] = machine_info();
  write_summary(out, s);
  folder.commit();  // a program beyond the strokes still gets its report, then the error
  if (!travel.empty()) {
    const std::size_t all = loaded.reader == "cl" ? travel.size() : verdict.beyond_stroke_count;
    throw InputError(travel.front().what + (all > 1 ? " (and " + std::to_string(all - 1) + " more; summary.json lists " +
                                                          (all > travel.size() ? "the first " + std::to_string(travel.size()) : std::string("them")) + ")"
                                                    : std::string()));
  }
  return s;
}

}  // namespace drom::machine
