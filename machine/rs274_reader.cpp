#include "machine/rs274_reader.hpp"

#include "machine/gcode_reader.hpp"
#include "support/input_error.hpp"

#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <fcntl.h>
#include <fstream>
#include <sstream>
#include <spawn.h>
#include <sys/wait.h>
#include <thread>
#include <unistd.h>

extern char** environ;

namespace drom::machine {

namespace fs = std::filesystem;

namespace {

// Line numbers are written as N words offset by this, so that N words of subroutine files (which
// are not renumbered) cannot be mistaken for a line of the program.
constexpr long long kLineBase = 100000000;

std::string find_executable(const Rs274Options& options) {
  if (!options.executable.empty()) return options.executable;
  if (const char* env = std::getenv("DROM_RS274"); env && *env) return env;
  if (const char* path = std::getenv("PATH")) {
    std::stringstream ss(path);
    std::string dir;
    while (std::getline(ss, dir, ':')) {
      const fs::path candidate = fs::path(dir.empty() ? "." : dir) / "rs274";
      if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
    }
  }
  return {};
}

// A scratch folder removed on scope exit.
struct ScratchFolder {
  fs::path path;
  ScratchFolder() {
    std::string pattern = (fs::temp_directory_path() / "drom-rs274-XXXXXX").string();
    if (!::mkdtemp(pattern.data())) throw std::runtime_error("cannot create a scratch folder for rs274: " + std::string(std::strerror(errno)));
    path = pattern;
  }
  ~ScratchFolder() {
    std::error_code ec;
    fs::remove_all(path, ec);
  }
};

// The program with every line's number as an N word (an N word already there is replaced).
std::string numbered_copy(const std::string& text) {
  std::istringstream in(text);
  std::ostringstream out;
  std::string line;
  long long n = 0;
  while (std::getline(in, line)) {
    ++n;
    std::size_t i = line.find_first_not_of(" \t\r");
    if (i == std::string::npos || line[i] == '%') {
      out << line << '\n';
      continue;
    }
    std::string head = line.substr(0, i);
    if (line[i] == '/') head += line[i++];
    if ((line[i] == 'N' || line[i] == 'n') && i + 1 < line.size() && std::isdigit(static_cast<unsigned char>(line[i + 1]))) {
      ++i;
      while (i < line.size() && (std::isdigit(static_cast<unsigned char>(line[i])) || line[i] == '.')) ++i;
    }
    out << head << 'N' << (kLineBase + n) << ' ' << line.substr(i) << '\n';
  }
  return out.str();
}

// Runs the command with stdout and stderr into `output` and `home` as its HOME; returns its exit
// status, or -1 on timeout. LinuxCNC keeps its tool table in a file mapped at $HOME/.tool.mmap, one for
// every rs274 of the user, and unlinks it as each ends: two reads at once (drom jobs side by side,
// ctest -j) swapped tool tables ("Requested tool 1 not found in the tool table"). Each rs274 gets its
// own scratch folder as HOME.
int run_with_timeout(const std::vector<std::string>& argv, const fs::path& output, std::chrono::seconds timeout, const fs::path& home) {
  std::vector<std::string> environment;
  for (char** e = environ; *e != nullptr; ++e)
    if (std::strncmp(*e, "HOME=", 5) != 0) environment.emplace_back(*e);
  environment.push_back("HOME=" + home.string());
  std::vector<char*> env;
  for (auto& e : environment) env.push_back(e.data());
  env.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, 1, output.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, 1, 2);
  posix_spawn_file_actions_addopen(&actions, 0, "/dev/null", O_RDONLY, 0);
  std::vector<char*> args;
  for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  pid_t pid = 0;
  const int rc = posix_spawn(&pid, args[0], &actions, nullptr, args.data(), env.data());
  posix_spawn_file_actions_destroy(&actions);
  if (rc != 0) throw std::runtime_error("cannot run " + argv[0] + ": " + std::strerror(rc));
  const auto deadline = std::chrono::steady_clock::now() + timeout;
  int status = 0;
  for (auto pause = std::chrono::milliseconds(1);; pause = std::min(pause * 2, std::chrono::milliseconds(50))) {
    const pid_t done = ::waitpid(pid, &status, WNOHANG);
    if (done == pid) break;
    if (std::chrono::steady_clock::now() > deadline) {
      ::kill(pid, SIGKILL);
      ::waitpid(pid, &status, 0);
      return -1;
    }
    std::this_thread::sleep_for(pause);
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
}

// One canonical call: "   12 N100000007STRAIGHT_FEED(1.0000, ...)".
struct Call {
  long long n = -1;  // the N word, -1 when none
  std::string name, args;
};

bool parse_call(const std::string& line, Call& call) {
  std::size_t i = line.find_first_not_of(' ');
  if (i == std::string::npos || !std::isdigit(static_cast<unsigned char>(line[i]))) return false;
  while (i < line.size() && std::isdigit(static_cast<unsigned char>(line[i]))) ++i;
  while (i < line.size() && line[i] == ' ') ++i;
  if (i >= line.size() || line[i] != 'N') return false;
  ++i;
  if (line.compare(i, 5, ".....") == 0) {
    call.n = -1;
    i += 5;
  } else {
    const std::size_t start = i;
    while (i < line.size() && std::isdigit(static_cast<unsigned char>(line[i]))) ++i;
    if (i == start) return false;
    // drom numbers the copy it hands rs274 from kLineBase; a number beyond that is no line of ours.
    if (i - start > 12) call.n = -1;
    else call.n = std::stoll(line.substr(start, i - start));
  }
  while (i < line.size() && line[i] == ' ') ++i;
  const std::size_t open = line.find('(', i), close = line.rfind(')');
  if (open == std::string::npos || close == std::string::npos || close < open) return false;
  call.name = line.substr(i, open - i);
  call.args = line.substr(open + 1, close - open - 1);
  return !call.name.empty();
}

std::vector<double> numbers(const std::string& args) {
  std::vector<double> v;
  const char* p = args.c_str();
  while (*p) {
    // A number starts with a digit, a sign or a point: strtod alone would also read words ("inf",
    // "nan", "infinity") as numbers.
    if (!std::isdigit(static_cast<unsigned char>(*p)) && *p != '-' && *p != '+' && *p != '.') {
      ++p;
      continue;
    }
    char* end = nullptr;
    const double x = std::strtod(p, &end);
    if (end == p) {
      ++p;
      continue;
    }
    v.push_back(x);
    p = end;
  }
  return v;
}

int line_of(long long n) { return n >= kLineBase && n - kLineBase <= 100000000 ? static_cast<int>(n - kLineBase) : 0; }

}  // namespace

bool rs274_available(const Rs274Options& options) { return !find_executable(options).empty(); }

Rs274Run run_rs274(const fs::path& program_path, const Rs274Options& options) {
  const std::string origin = program_path.string();
  std::ifstream in(program_path);
  if (!in) throw InputError(origin + ": cannot open program");
  std::ostringstream text;
  text << in.rdbuf();
  const std::string exe = find_executable(options);
  if (exe.empty())
    throw InputError(origin + ": this program needs LinuxCNC's interpreter (it is outside drom's plain G-code subset), and rs274 is not installed: apt-get install linuxcnc-uspace");

  ScratchFolder scratch;
  const fs::path copy = scratch.path / "program.ngc", ini = scratch.path / "drom.ini", table = scratch.path / "tools.tbl",
                 vars = scratch.path / "drom.var", output = scratch.path / "canonical.txt";
  {
    std::ofstream(copy) << numbered_copy(text.str());
    std::string paths = fs::absolute(program_path).parent_path().string();
    for (const auto& p : options.subroutine_paths) {
      paths += ':';  // appended apart: GCC 12's -Wrestrict misreads ":" + std::string&& once inlined here
      paths += fs::absolute(p).string();
    }
    std::ofstream(ini) << "[RS274NGC]\nSUBROUTINE_PATH = " << paths << "\nPARAMETER_FILE = " << vars.string() << "\n";
    std::ofstream(vars) << "";
    std::ofstream tools(table);
    for (int t = 1; t < 1000; ++t) {
      const auto it = options.tool_diameters.find(t);
      // rs274 reads the table in inches. Each tool's length is its number (in inches), so that the
      // offset rs274 reports after G43 H names the H used; lengths do not move the canonical positions.
      tools << 'T' << t << " P" << t << " Z" << t << " D" << (it == options.tool_diameters.end() ? 0.0 : it->second / 25.4) << " ;\n";
    }
  }
  int status = run_with_timeout({exe, "-i", ini.string(), "-t", table.string(), "-g", copy.string()}, output, options.timeout, scratch.path);
  // Killed by a signal (seen once here, a SIGBUS under heavy load): run it again once, afresh.
  if (status > 128) {
    std::ofstream(vars) << "";
    status = run_with_timeout({exe, "-i", ini.string(), "-t", table.string(), "-g", copy.string()}, output, options.timeout, scratch.path);
  }
  if (status == -1)
    throw InputError(origin + ": LinuxCNC's interpreter did not finish within " + std::to_string(options.timeout.count()) +
                     " s: an endless loop (O-word while/do/repeat)?");
  std::ifstream in_calls(output, std::ios::binary);
  std::ostringstream calls;
  calls << in_calls.rdbuf();
  return {calls.str(), status};
}

NcProgram read_with_rs274(const fs::path& program_path, const Rs274Options& options) {
  const Rs274Run run = run_rs274(program_path, options);
  return parse_rs274_calls(run.calls, run.status, program_path.string());
}

NcProgram parse_rs274_calls(std::string_view calls, int status, const std::string& origin) {
  std::istringstream canon{std::string(calls)};
  NcProgram program;
  program.origin = origin;
  program.reader = "rs274";
  double unit = 1.0;  // mm per program length unit
  std::array<double, 9> g5x{}, g92{}, position{};
  int plane = 17;
  double feed = 0, spindle_speed = 0;
  bool per_revolution = false, stop_pending = false;
  double synchronized = 0;  // units per spindle revolution while motion follows the spindle (G33, G33.1), else 0
  int tool_length_offset = 0;
  PathControl control = PathControl::Blend;
  double tolerance = -1;
  bool exact_stop = false;
  std::vector<std::string> complaints;
  int last_line = 0;
  std::string line;
  auto fail = [&](int at, const std::string& message) -> void {
    if (at > 0) throw InputError(origin + ":" + std::to_string(at) + ": " + message);
    if (last_line > 0) throw InputError(origin + ":" + std::to_string(last_line) + ": (in a subroutine file it calls) " + message);
    throw InputError(origin + ": " + message);
  };
  auto machine_axes = [&](const std::vector<double>& v, std::size_t from) {
    std::array<double, 9> p = position;
    for (std::size_t k = 0; k < 9 && from + k < v.size(); ++k) p[k] = v[from + k] * (k < 3 || k >= 6 ? unit : 1.0) + g5x[k] + g92[k];
    return p;
  };
  auto add_move = [&](MoveType type, const std::array<double, 9>& target, int at) {
    for (int k = 6; k < 9; ++k)
      if (std::abs(target[k] - position[k]) > 1e-9) fail(at, std::string("the program moves the ") + "UVW"[k - 6] + " axis, which drom's machines do not have");
    NcMove m;
    m.type = type;
    for (int k = 0; k < 6; ++k) m.start[k] = position[k], m.end[k] = target[k];
    m.line = at;
    m.control = exact_stop ? PathControl::ExactStop : control;
    m.blend_tolerance = tolerance;
    m.stop_before = stop_pending;
    m.tool_length_offset = tool_length_offset;
    stop_pending = exact_stop;
    if (type != MoveType::Rapid) {
      const bool linear = (m.end.head<3>() - m.start.head<3>()).norm() > 1e-12 || type == MoveType::Arc;
      // The interpreter's feed is per minute of its reference: program length units, or degrees.
      double f = feed * (linear ? unit : 1.0);
      if (per_revolution) f *= spindle_speed;
      if (synchronized > 0) f = synchronized * unit * spindle_speed;
      if (!(f > 0)) fail(at, "a cutting move with a zero feed rate");
      m.feed = f;
    }
    position = target;
    return m;
  };
  while (std::getline(canon, line)) {
    Call c;
    if (!parse_call(line, c)) {
      if (line != "executing" && !line.empty()) complaints.push_back(line);
      continue;
    }
    const int at = line_of(c.n);
    if (at > 0) last_line = at;
    const std::string& f = c.name;
    if (f != "COMMENT" && f != "MESSAGE")
      for (const double x : numbers(c.args))
        if (!std::isfinite(x)) fail(at, "rs274 printed " + f + " with a value beyond any finite number: " + c.args.substr(0, 200));
    if (f == "STRAIGHT_TRAVERSE" || f == "STRAIGHT_FEED") {
      const auto v = numbers(c.args);
      if (v.size() < 6) fail(at, "rs274 printed " + f + " with " + std::to_string(v.size()) + " values");
      program.moves.push_back(add_move(f == "STRAIGHT_FEED" ? MoveType::Linear : MoveType::Rapid, machine_axes(v, 0), at));
    } else if (f == "ARC_FEED") {
      const auto v = numbers(c.args);
      if (v.size() < 9) fail(at, "rs274 printed ARC_FEED with " + std::to_string(v.size()) + " values");
      const PlaneAxes p = plane_axes(plane);
      std::array<double, 9> target = position;
      target[p.first] = v[0] * unit + g5x[p.first] + g92[p.first];
      target[p.second] = v[1] * unit + g5x[p.second] + g92[p.second];
      target[p.normal] = v[5] * unit + g5x[p.normal] + g92[p.normal];
      for (int k = 3; k < 6; ++k) target[k] = v[3 + k] + g5x[k] + g92[k];
      for (std::size_t k = 6; k < 9 && k + 3 < v.size(); ++k) target[k] = v[k + 3] * unit + g5x[k] + g92[k];
      NcMove m = add_move(MoveType::Arc, target, at);
      m.plane = plane;
      m.rotation = static_cast<int>(std::lround(v[4]));
      m.centre = m.start.head<3>();
      m.centre[p.first] = v[2] * unit + g5x[p.first] + g92[p.first];
      m.centre[p.second] = v[3] * unit + g5x[p.second] + g92[p.second];
      program.moves.push_back(m);
    } else if (f == "DWELL") {
      const auto v = numbers(c.args);
      NcMove m;
      m.type = MoveType::Dwell;
      for (int k = 0; k < 6; ++k) m.start[k] = m.end[k] = position[k];
      m.dwell = v.empty() ? 0 : v[0];
      m.line = at;
      program.moves.push_back(m);
      stop_pending = true;
    } else if (f == "USE_LENGTH_UNITS") {
      unit = c.args.find("INCHES") != std::string::npos ? 25.4 : c.args.find("CM") != std::string::npos ? 10.0 : 1.0;
    } else if (f == "SET_G5X_OFFSET" || f == "SET_G92_OFFSET") {
      auto v = numbers(c.args);
      if (f == "SET_G5X_OFFSET" && !v.empty()) v.erase(v.begin());  // the coordinate system's index
      auto& offset = f == "SET_G5X_OFFSET" ? g5x : g92;
      for (std::size_t k = 0; k < 9; ++k) offset[k] = k < v.size() ? v[k] * (k < 3 || k >= 6 ? unit : 1.0) : 0.0;
    } else if (f == "SET_XY_ROTATION") {
      const auto v = numbers(c.args);
      if (!v.empty() && std::abs(v[0]) > 1e-12) fail(at, "a rotated coordinate system (G10 L2 R) is not supported");
    } else if (f == "SELECT_PLANE") {
      if (c.args.find("XY") != std::string::npos) plane = 17;
      else if (c.args.find("XZ") != std::string::npos) plane = 18;
      else if (c.args.find("YZ") != std::string::npos) plane = 19;
      else fail(at, "arcs in the " + c.args + " plane (U, V, W axes) are not supported");
    } else if (f == "SET_FEED_RATE") {
      const auto v = numbers(c.args);
      feed = v.empty() ? 0 : v[0];
    } else if (f == "SET_FEED_MODE") {
      const auto v = numbers(c.args);
      per_revolution = v.size() >= 2 && v[1] == 1;
    } else if (f == "SET_SPINDLE_SPEED") {
      const auto v = numbers(c.args);
      spindle_speed = v.empty() ? 0 : v.back();
    } else if (f == "SET_MOTION_CONTROL_MODE") {
      exact_stop = c.args.find("EXACT_STOP") != std::string::npos;
      if (c.args.find("EXACT_PATH") != std::string::npos) control = PathControl::Blend, tolerance = 0;
      if (c.args.find("CONTINUOUS") != std::string::npos) {
        const auto v = numbers(c.args);
        control = PathControl::Blend;
        tolerance = !v.empty() && v[0] > 0 ? v[0] * unit : -1;  // G64 without P: the machine's own
      }
    } else if (f == "USE_TOOL_LENGTH_OFFSET") {
      const auto v = numbers(c.args);
      tool_length_offset = v.size() >= 3 ? static_cast<int>(std::lround(v[2] * unit / 25.4)) : 0;
    } else if (f == "CHANGE_TOOL" || f == "PROGRAM_STOP" || f == "OPTIONAL_PROGRAM_STOP" || f == "PROGRAM_END" || f == "PALLET_SHUTTLE") {
      stop_pending = true;
    } else if (f == "STRAIGHT_PROBE") {
      fail(at, "not a milling program: it probes (G38), which drom does not model");
    } else if (f == "START_SPEED_FEED_SYNC" || f == "START_SPEED_FEED_SYNCH") {
      const auto v = numbers(c.args);
      synchronized = v.empty() ? 0 : v[0];
      if (!(spindle_speed > 0)) fail(at, "spindle-synchronized motion (G33, G33.1) with the spindle stopped");
    } else if (f == "STOP_SPEED_FEED_SYNCH" || f == "STOP_SPEED_FEED_SYNC") {
      synchronized = 0;
    } else if (f == "RIGID_TAP") {
      // G33.1: down to the hole's bottom at the pitch times the spindle speed, the spindle reverses,
      // and the tap comes back out along the same line.
      const auto v = numbers(c.args);
      if (v.size() < 3) fail(at, "rs274 printed RIGID_TAP with " + std::to_string(v.size()) + " values");
      std::array<double, 9> bottom = position;
      for (int k = 0; k < 3; ++k) bottom[k] = v[k] * unit + g5x[k] + g92[k];
      const std::array<double, 9> top = position;
      stop_pending = true;
      program.moves.push_back(add_move(MoveType::Linear, bottom, at));
      stop_pending = true;
      program.moves.push_back(add_move(MoveType::Linear, top, at));
    }
  }
  if (status != 0) {
    std::string message = complaints.empty() ? (status > 128 ? "rs274 was killed by signal " + std::to_string(status - 128) : "rs274 stopped with status " + std::to_string(status))
                                             : complaints.front();
    int at = last_line;
    if (complaints.size() > 1) {
      // rs274 prints the offending block after its message; our N word in it gives the line.
      const std::string& block = complaints[1];
      const auto pos = block.find_first_of("Nn");
      if (pos != std::string::npos) {
        const long long n = std::atoll(block.c_str() + pos + 1);
        if (n >= kLineBase) at = line_of(n);
      }
    }
    fail(at, "LinuxCNC's interpreter: " + message);
  }
  settle_program_start(program);
  return program;
}

}  // namespace drom::machine
