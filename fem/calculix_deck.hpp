#pragma once
// One machining state of an ElasticProblem as a CalculiX (ccx 2.x) input deck, and ccx's printed
// displacements read back: the same station solved by an FE code anyone can run, to compare answers
// and times (docs/benchmarks.md).
//
// The deck holds the stock's C3D20 mesh (drom's Hex20 node order is ccx's), the equilibrated stock's
// stress sigma0 = sigma_R + C eps(u0) at ccx's 27 integration points (*INITIAL CONDITIONS,
// TYPE=STRESS), the clamps (*BOUNDARY), and one linear *STATIC step that removes the machined
// elements (*MODEL CHANGE, TYPE=ELEMENT, REMOVE) and prints U of every node. ccx then solves
//   K(a) u = -sum_e a_e int B^T sigma0,
// drom's equation (docs/design.md §3): a partly machined element (0 < a < 1) gets its own material of
// modulus a E and the initial stress a sigma0, so that both its stiffness and its load scale by a.
// The one difference is quadrature: ccx integrates sigma0 with 3 Gauss points a direction, exact for
// stress profiles up to degree 3 through an element; drom uses a rule exact for the profile's degree.
#include "fem/elastic_problem.hpp"

#include <Eigen/Core>

#include <filesystem>
#include <string>
#include <vector>

namespace drom::fem {

struct CalculixDeckStats {
  int nodes = 0, elements = 0;
  int removed = 0;   // elements in the *MODEL CHANGE, REMOVE set
  int partial = 0;   // elements with 0 < a < 1: a material of their own
  int fixed_dofs = 0;
  double megabytes = 0;
};

// ccx's 27 integration points of a C3D20, in its order (the first reference coordinate fastest).
std::vector<Eigen::Vector3d> c3d20_integration_points();

// Writes the deck (atomically) for the problem's current activity and fixed dofs, loaded by profile
// `profile`. The problem must be equilibrated and its mesh made of Hex20 elements (std::invalid_argument
// otherwise: ccx has no 27-node brick, and its C3D10 integration points are another order).
CalculixDeckStats write_calculix_deck(const std::filesystem::path& path, const ElasticProblem& problem, const Material& material, int profile,
                                      const std::string& heading);

// The nodal displacements ccx printed (*NODE PRINT, U) into its .dat file, as 3 * node + component
// (node numbers are drom's + 1). Throws InputError naming the file and line when it holds no
// displacement block, a malformed row, a node outside 1..node_count, or a node printed twice.
Eigen::VectorXd read_calculix_displacements(const std::filesystem::path& dat, int node_count);

struct CalculixRun {
  Eigen::VectorXd displacement;  // as read_calculix_displacements
  double wall_seconds = 0;       // the whole ccx process
  double reported_seconds = 0;   // ccx's own "Total CalculiX Time" (0 if it printed none)
  std::string log;               // what ccx printed
};

// Runs `ccx -i <stem>` in the deck's folder on `threads` threads (OMP_NUM_THREADS and ccx's
// CCX_NPROC_* variables) and reads its displacements. Throws std::runtime_error when ccx is not on
// the PATH (Debian: calculix-ccx, which scripts/setup installs) or reports an error.
CalculixRun run_calculix(const std::filesystem::path& deck, int node_count, int threads = 1);

}  // namespace drom::fem
