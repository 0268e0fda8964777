#pragma once
// Turns a case into the fem/ objects it describes: part shape, mesh, material, stress profile, clamps.
#include "case_file/case.hpp"
#include "fem/element_operators.hpp"
#include "fem/mesh.hpp"
#include "levelset/material_removal.hpp"
#include "geometry/part_shape.hpp"
#include "paths/cutter/tool_assembly.hpp"
#include "levelset/toolpath.hpp"
#include "fem/residual_stress.hpp"
#include "pgd/pgd_solver.hpp"

#include <vector>

namespace drom::offline {

struct PartModel {
  fem::PartShape shape;
  fem::Mesh mesh;
  fem::Material material;
  std::vector<int> degrees;     // the Legendre basis
  fem::StressProfile profile;   // the case's profile in that basis
  fem::StressProfile truth_profile;  // the real part's ([truth], times its amplitude; else the case's)
};

PartModel build_part(const case_file::Case& c);
// Dofs fixed by the case's [[clamps]]; throws InputError for a clamp that selects nothing.
std::vector<int> clamp_dofs(const case_file::Case& c, const PartModel& part);
fem::ProfileParity parity_of(const case_file::Case& c);

paths::ToolAssembly build_tool(const case_file::Case& c);
// The case's G-code program if it names one, otherwise the generated pocket toolpath.
levelset::Toolpath build_toolpath(const case_file::Case& c, const PartModel& part);
levelset::Workpiece build_workpiece(const case_file::Case& c, const PartModel& part, double voxel_size);
// The case's voxel size, or one chosen from the tool, the depth of cut and the thinnest element.
double voxel_size_for(const case_file::Case& c, const PartModel& part);
// The PGD's settings: its defaults, with the keys the case's [solver] gives.
pgd::PgdSettings pgd_settings(const case_file::Case& c);

}  // namespace drom::offline
