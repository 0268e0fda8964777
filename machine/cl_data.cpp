#include "machine/cl_data.hpp"

#include "support/input_error.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <map>
#include <numbers>
#include <sstream>

namespace drom::machine {

namespace fs = std::filesystem;

namespace {

std::string upper(std::string s) {
  for (char& c : s) c = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  return s;
}

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r"), b = s.find_last_not_of(" \t\r");
  return a == std::string::npos ? std::string() : s.substr(a, b - a + 1);
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> parts;
  std::stringstream ss(s);
  std::string p;
  while (std::getline(ss, p, sep)) parts.push_back(trim(p));
  return parts;
}

double number(const std::string& s, const std::string& where, const std::string& what) {
  std::size_t used = 0;
  double v = 0;
  try {
    v = std::stod(s, &used);
  } catch (const std::exception&) {
    throw InputError(where + what + ": expected a number, got '" + printable(s) + "'");
  }
  if (used != s.size() || !std::isfinite(v)) throw InputError(where + what + ": expected a finite number, got '" + printable(s) + "'");
  // A kilometre, or 10^6 mm/min, is beyond any machine: a corrupted file (and squares stay finite).
  if (std::abs(v) > 1e6) throw InputError(where + what + ": " + printable(s) + " is beyond any machine (|value| <= 1e6)");
  return v;
}

Eigen::Vector3d unit_axis(const Eigen::Vector3d& v, const std::string& where) {
  const double n = v.norm();
  if (!(n > 1e-9)) throw InputError(where + "the tool axis (i, j, k) is zero");
  if (std::abs(n - 1) > 1e-3) throw InputError(where + "the tool axis (i, j, k) is not a unit vector (length " + std::to_string(n) + ")");
  return v / n;
}

}  // namespace

bool is_cl_file(const fs::path& path) {
  const std::string e = upper(path.extension().string());
  return e == ".APT" || e == ".CL" || e == ".CLS" || e == ".APTSOURCE" || e == ".CSV";
}

ClProgram parse_apt_cl(const std::string& text, const std::string& origin) {
  ClProgram cl;
  cl.origin = origin;
  std::istringstream in(text);
  std::string raw, statement;
  int line_no = 0, statement_line = 0;
  double unit = 1.0, feed = 0;
  bool rapid_next = false;
  Eigen::Vector3d axis = Eigen::Vector3d::UnitZ();
  // Statements CAM systems write that change nothing of the tool's motion.
  static const char* const kInert[] = {"PARTNO", "PPRINT", "MACHIN", "MULTAX", "CUTTER", "LOADTL", "SPINDL", "COOLNT", "INSERT", "CLRSRF",
                                       "SELCTL", "TOOLNO", "TPRINT", "OPSKIP", "END",    "FINI",   "STOP",   "OPSTOP", "CUTCOM", "DISPLY",
                                       "PITCH",  "TURRET", "TITLES", "REMARK", "OPERATION_NAME"};
  while (std::getline(in, raw)) {
    ++line_no;
    std::string line = raw;
    if (const auto c = line.find("$$"); c != std::string::npos) line.erase(c);
    line = trim(line);
    if (line.empty()) continue;
    if (statement.empty()) statement_line = line_no;
    if (line.back() == '$') {  // continued on the next line
      statement += line.substr(0, line.size() - 1);
      continue;
    }
    statement += line;
    const std::string where = origin + ":" + std::to_string(statement_line) + ": ";
    const auto slash = statement.find('/');
    const std::string major = upper(trim(statement.substr(0, slash)));
    const std::vector<std::string> args = slash == std::string::npos ? std::vector<std::string>{} : split(statement.substr(slash + 1), ',');
    statement.clear();
    if (major == "GOTO" || major == "FROM") {
      if (args.size() != 3 && args.size() != 6) throw InputError(where + major + " needs x, y, z or x, y, z, i, j, k; got " + std::to_string(args.size()) + " values");
      ClPoint p;
      p.line = statement_line;
      p.pose.tip = Eigen::Vector3d(number(args[0], where, "x"), number(args[1], where, "y"), number(args[2], where, "z")) * unit;
      if (args.size() == 6) axis = unit_axis({number(args[3], where, "i"), number(args[4], where, "j"), number(args[5], where, "k")}, where);
      p.pose.axis = axis;
      p.rapid = rapid_next || major == "FROM" || cl.points.empty();
      if (!p.rapid && !(feed > 0)) throw InputError(where + "a cutting GOTO before any FEDRAT");
      p.feed = feed;
      rapid_next = false;
      cl.points.push_back(p);
    } else if (major == "FEDRAT") {
      if (args.empty()) throw InputError(where + "FEDRAT needs a feed");
      feed = number(args[0], where, "FEDRAT");
      if (!(feed > 0)) throw InputError(where + "FEDRAT must be positive");
      const std::string mode = args.size() > 1 ? upper(args[1]) : "MMPM";
      if (mode == "IPM") feed *= 25.4;
      else if (mode != "MMPM") throw InputError(where + "FEDRAT mode '" + printable(args[1]) + "': expected MMPM or IPM (per-revolution feeds are not modelled)");
    } else if (major == "RAPID") {
      rapid_next = true;
    } else if (major == "UNITS") {
      const std::string u = args.empty() ? "" : upper(args[0]);
      if (u == "MM") unit = 1.0;
      else if (u == "INCHES" || u == "INCH") unit = 25.4;
      else throw InputError(where + "UNITS: expected MM or INCHES");
    } else if (major == "TLAXIS") {
      if (args.size() != 3) throw InputError(where + "TLAXIS needs i, j, k");
      axis = unit_axis({number(args[0], where, "i"), number(args[1], where, "j"), number(args[2], where, "k")}, where);
    } else if (std::find(std::begin(kInert), std::end(kInert), major) == std::end(kInert)) {
      throw InputError(where + "CL statement '" + printable(major) + "' is not understood (motion: GOTO, FROM, RAPID, FEDRAT, UNITS, TLAXIS)");
    }
  }
  if (!statement.empty()) throw InputError(origin + ":" + std::to_string(statement_line) + ": the file ends inside a statement continued with '$'");
  if (cl.points.empty()) throw InputError(origin + ": no GOTO in the CL file");
  return cl;
}

ClProgram parse_cl_csv(const std::string& text, const std::string& origin) {
  ClProgram cl;
  cl.origin = origin;
  std::istringstream in(text);
  std::string raw;
  int line_no = 0;
  std::map<std::string, std::size_t> column;
  while (std::getline(in, raw)) {
    ++line_no;
    const std::string line = trim(raw);
    if (line.empty() || line[0] == '#') continue;
    const auto cells = split(line, ',');
    const std::string where = origin + ":" + std::to_string(line_no) + ": ";
    if (column.empty()) {
      // A column named twice would leave column.size() short of the header's cells (a fuzz finding: a
      // short row was then read past its end).
      for (std::size_t c = 0; c < cells.size(); ++c)
        if (!column.emplace(cells[c], c).second) throw InputError(where + "the CL table's header names column '" + printable(cells[c]) + "' twice");
      for (const char* need : {"x", "y", "z", "i", "j", "k", "feed"})
        if (!column.count(need)) throw InputError(where + "the CL table's header needs the columns x, y, z, i, j, k, feed; '" + need + "' is missing");
      continue;
    }
    if (cells.size() < column.size()) throw InputError(where + "expected " + std::to_string(column.size()) + " cells, got " + std::to_string(cells.size()));
    auto cell = [&](const char* name) { return number(cells[column[name]], where, name); };
    ClPoint p;
    p.line = line_no;
    p.pose.tip = {cell("x"), cell("y"), cell("z")};
    p.pose.axis = unit_axis({cell("i"), cell("j"), cell("k")}, where);
    p.feed = cell("feed");
    if (p.feed < 0) throw InputError(where + "feed must be >= 0 (0 marks a rapid)");
    p.rapid = p.feed == 0 || cl.points.empty();
    cl.points.push_back(p);
  }
  if (cl.points.empty()) throw InputError(origin + ": no CL point in the table");
  return cl;
}

ClProgram read_cl_file(const fs::path& path) {
  std::ifstream in(path);
  if (!in) throw InputError(path.string() + ": cannot open CL file");
  std::ostringstream ss;
  ss << in.rdbuf();
  return upper(path.extension().string()) == ".CSV" ? parse_cl_csv(ss.str(), path.string()) : parse_apt_cl(ss.str(), path.string());
}

std::string cl_csv(const ClProgram& program) {
  std::string out = "x,y,z,i,j,k,feed\n";
  char buf[256];
  for (const ClPoint& p : program.points) {
    std::snprintf(buf, sizeof buf, "%.6f,%.6f,%.6f,%.9f,%.9f,%.9f,%.3f\n", p.pose.tip.x(), p.pose.tip.y(), p.pose.tip.z(), p.pose.axis.x(), p.pose.axis.y(),
                  p.pose.axis.z(), p.rapid ? 0.0 : p.feed);
    out += buf;
  }
  return out;
}

ClOnMachine cl_to_machine_program(const ClProgram& cl, const Kinematics& kin) {
  ClOnMachine out;
  out.program.origin = cl.origin;
  std::vector<ClPose> poses;
  poses.reserve(cl.points.size());
  for (const ClPoint& p : cl.points) poses.push_back(p.pose);
  out.joints = inverse_path(kin, poses);
  for (std::size_t i = 1; i < cl.points.size(); ++i) {
    const ClPoint& p = cl.points[i];
    MachineBlock b;
    b.type = p.rapid ? MoveType::Rapid : MoveType::Linear;
    b.start = out.joints.joints[i - 1];
    b.end = out.joints.joints[i];
    b.line = p.line;
    if (!p.rapid) {
      double travel = (p.pose.tip - cl.points[i - 1].pose.tip).norm();
      if (!(travel > 1e-9)) {
        // The tip stays: the feed applies to the rotary travel in degrees (LinuxCNC's reference).
        travel = 0;
        for (int j = 3; j < kin.machine().joint_count(); ++j) travel += std::pow((b.end[j] - b.start[j]) * 180 / std::numbers::pi, 2);
        travel = std::sqrt(travel);
      }
      // A repeated pose moves nothing: no block (a G1 to where the tool is has no feed to give it).
      if (!(travel > 1e-9)) continue;
      b.programmed_duration = 60 * travel / p.feed;
    }
    out.program.blocks.push_back(b);
  }
  return out;
}

}  // namespace drom::machine
