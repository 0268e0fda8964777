#include "fem/calculix_deck.hpp"

#include "support/atomic_file.hpp"
#include "support/input_error.hpp"

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace drom::fem {

namespace {

// ccx's manual limits an input line to 132 characters; %.9e keeps a stress row (two ids and six
// values) under it, at 1e-10 relative, far below what the comparison measures.
void append_line(std::string& out, const char* format, auto... values) {
  char line[200];
  const int n = std::snprintf(line, sizeof line, format, values...);
  out.append(line, static_cast<std::size_t>(n));
}

// Element numbers in rows of 16 (ccx's set cards take at most 16 entries a line).
void append_ids(std::string& out, const std::vector<int>& ids) {
  for (std::size_t i = 0; i < ids.size(); ++i) {
    append_line(out, "%d", ids[i] + 1);
    out += (i + 1 == ids.size() || (i + 1) % 16 == 0) ? "\n" : ",";
  }
}

}  // namespace

std::vector<Eigen::Vector3d> c3d20_integration_points() {
  const double g = std::sqrt(0.6);
  const double x[3] = {-g, 0.0, g};
  std::vector<Eigen::Vector3d> points;
  for (int k = 0; k < 3; ++k)
    for (int j = 0; j < 3; ++j)
      for (int i = 0; i < 3; ++i) points.emplace_back(x[i], x[j], x[k]);
  return points;
}

CalculixDeckStats write_calculix_deck(const std::filesystem::path& path, const ElasticProblem& problem, const Material& material, int profile,
                                      const std::string& heading) {
  const Mesh& mesh = problem.mesh();
  if (mesh.type != ElementType::Hex20)
    throw std::invalid_argument(std::string("write_calculix_deck: the mesh is made of ") + element_name(mesh.type) +
                                " elements; the CalculiX deck supports Hex20 (C3D20) only");
  if (profile < 0 || profile >= static_cast<int>(problem.profiles().size())) throw std::invalid_argument("write_calculix_deck: no such profile");
  const auto& activity = problem.activity();
  CalculixDeckStats stats;
  stats.nodes = mesh.node_count();
  stats.elements = mesh.element_count();

  std::string out;
  out += "*HEADING\n" + heading + "\n";
  out += "** Written by drom (fem/calculix_deck.hpp). Units: mm, MPa. Node and element numbers are drom's + 1.\n";
  out += "*NODE, NSET=NALL\n";
  for (int n = 0; n < mesh.node_count(); ++n) {
    const auto& x = mesh.nodes[static_cast<std::size_t>(n)];
    append_line(out, "%d,%.17g,%.17g,%.17g\n", n + 1, x.x(), x.y(), x.z());
  }
  // drom's Hex20 order (VTK's) is ccx's C3D20 order: corners of the bottom face counter-clockwise,
  // then of the top face, then the mid-edge nodes of the bottom, top and vertical edges.
  out += "*ELEMENT, TYPE=C3D20, ELSET=EALL\n";
  for (int e = 0; e < mesh.element_count(); ++e) {
    const auto nodes = mesh.element(e);
    append_line(out, "%d", e + 1);
    for (std::size_t a = 0; a < nodes.size(); ++a) {
      out += a == 15 ? ",\n" : ",";  // a continuation line (after a trailing comma) keeps both short
      append_line(out, "%d", nodes[a] + 1);
    }
    out += "\n";
  }
  std::vector<int> whole, removed, partial;
  for (int e = 0; e < mesh.element_count(); ++e) {
    const double a = activity[static_cast<std::size_t>(e)];
    if (a <= 0)
      removed.push_back(e);
    else if (a < 1)
      partial.push_back(e);
    if (a <= 0 || a >= 1) whole.push_back(e);
  }
  stats.removed = static_cast<int>(removed.size());
  stats.partial = static_cast<int>(partial.size());
  if (!whole.empty()) {
    out += "*ELSET, ELSET=WHOLE\n";
    append_ids(out, whole);
  }
  if (!removed.empty()) {
    out += "*ELSET, ELSET=REMOVED\n";
    append_ids(out, removed);
  }
  out += "*MATERIAL, NAME=STOCK\n*ELASTIC\n";
  append_line(out, "%.17g,%.17g\n", material.young_modulus, material.poisson_ratio);
  if (!whole.empty()) out += "*SOLID SECTION, ELSET=WHOLE, MATERIAL=STOCK\n";
  // A partly machined element: the stiffness and the load of the fraction a that is left.
  for (int e : partial) {
    const double a = activity[static_cast<std::size_t>(e)];
    append_line(out, "*ELSET, ELSET=P%d\n%d\n*MATERIAL, NAME=P%d\n*ELASTIC\n%.17g,%.17g\n*SOLID SECTION, ELSET=P%d, MATERIAL=P%d\n", e + 1, e + 1, e + 1,
                a * material.young_modulus, material.poisson_ratio, e + 1, e + 1);
  }
  // ccx's stress order is xx, yy, zz, xy, xz, yz; drom's Voigt order is xx, yy, zz, yz, xz, xy.
  out += "*INITIAL CONDITIONS, TYPE=STRESS\n";
  const auto points = c3d20_integration_points();
  for (int e = 0; e < mesh.element_count(); ++e) {
    const double a = activity[static_cast<std::size_t>(e)];
    if (a <= 0) continue;
    for (std::size_t q = 0; q < points.size(); ++q) {
      const Vector6d s = a * problem.initial_stress(profile, e, points[q]);
      append_line(out, "%d,%zu,%.9e,%.9e,%.9e,%.9e,%.9e,%.9e\n", e + 1, q + 1, s(0), s(1), s(2), s(5), s(4), s(3));
    }
  }
  out += "*STEP\n*STATIC, SOLVER=SPOOLES\n";
  if (!removed.empty()) out += "*MODEL CHANGE, TYPE=ELEMENT, REMOVE\nREMOVED\n";
  out += "*BOUNDARY\n";
  for (int d : problem.fixed_dofs()) append_line(out, "%d,%d,%d,0\n", d / 3 + 1, d % 3 + 1, d % 3 + 1);
  stats.fixed_dofs = static_cast<int>(problem.fixed_dofs().size());
  out += "*NODE PRINT, NSET=NALL\nU\n*END STEP\n";
  stats.megabytes = static_cast<double>(out.size()) / 1048576.0;
  write_file_atomically(path, out);
  return stats;
}

Eigen::VectorXd read_calculix_displacements(const std::filesystem::path& dat, int node_count) {
  std::ifstream in(dat);
  if (!in) throw InputError(dat.string() + ": cannot be read (CalculiX's .dat output was expected)");
  Eigen::VectorXd u = Eigen::VectorXd::Zero(3 * static_cast<Eigen::Index>(node_count));
  std::vector<char> seen(static_cast<std::size_t>(node_count), 0);
  std::string line;
  int line_number = 0;
  bool in_block = false, found = false;
  int rows = 0;
  while (std::getline(in, line)) {
    ++line_number;
    if (line.find("displacements (vx,vy,vz)") != std::string::npos) {
      if (found) break;  // a later step's or time's block: the first one is the station's
      in_block = found = true;
      continue;
    }
    if (!in_block) continue;
    if (line.find_first_not_of(" \t\r") == std::string::npos) {
      if (rows > 0) in_block = false;  // the blank line after the rows
      continue;
    }
    std::istringstream row(line);
    long node = 0;
    double x = 0, y = 0, z = 0;
    std::string rest;
    if (!(row >> node >> x >> y >> z) || (row >> rest) || !std::isfinite(x) || !std::isfinite(y) || !std::isfinite(z))
      throw InputError(dat.string() + ":" + std::to_string(line_number) + ": expected \"node ux uy uz\" with finite numbers, got \"" + printable(line) + "\"");
    if (node < 1 || node > node_count)
      throw InputError(dat.string() + ":" + std::to_string(line_number) + ": node " + std::to_string(node) + " is outside 1.." + std::to_string(node_count));
    if (seen[static_cast<std::size_t>(node - 1)]++)
      throw InputError(dat.string() + ":" + std::to_string(line_number) + ": node " + std::to_string(node) + " printed twice");
    u.segment<3>(3 * (node - 1)) = Eigen::Vector3d(x, y, z);
    ++rows;
  }
  if (!found) throw InputError(dat.string() + ": no \"displacements (vx,vy,vz)\" block (the deck's *NODE PRINT, U)");
  return u;
}

CalculixRun run_calculix(const std::filesystem::path& deck, int node_count, int threads) {
  if (std::system("command -v ccx > /dev/null 2>&1") != 0)
    throw std::runtime_error("ccx (CalculiX) is not on the PATH: install Debian's calculix-ccx (scripts/setup does)");
  const auto folder = std::filesystem::absolute(deck).parent_path();
  auto quoted = [](const std::string& text) {
    std::string q = "'";
    for (char c : text) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return q + "'";
  };
  const std::string n = std::to_string(threads);
  const std::string command = "cd " + quoted(folder.string()) + " && OMP_NUM_THREADS=" + n + " CCX_NPROC_STIFFNESS=" + n + " CCX_NPROC_EQUATION_SOLVER=" + n +
                              " CCX_NPROC_RESULTS=" + n + " ccx -i " + quoted(deck.stem().string()) + " 2>&1";
  const auto dat = folder / (deck.stem().string() + ".dat");
  std::filesystem::remove(dat);  // never an older run's answer
  CalculixRun run;
  const auto start = std::chrono::steady_clock::now();
  FILE* pipe = popen(command.c_str(), "r");
  if (!pipe) throw std::runtime_error("cannot start ccx: " + command);
  char buffer[4096];
  while (std::fgets(buffer, sizeof buffer, pipe)) run.log += buffer;
  const int status = pclose(pipe);
  run.wall_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  // ccx exits 0 after some errors too: its "*ERROR" lines say so.
  if (status != 0 || run.log.find("*ERROR") != std::string::npos)
    throw std::runtime_error("ccx failed on " + deck.string() + ":\n" + run.log.substr(run.log.size() > 2000 ? run.log.size() - 2000 : 0));
  if (const auto at = run.log.find("Total CalculiX Time:"); at != std::string::npos) run.reported_seconds = std::atof(run.log.c_str() + at + 20);
  run.displacement = read_calculix_displacements(dat, node_count);
  return run;
}

}  // namespace drom::fem
