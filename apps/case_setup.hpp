#pragma once
// Turns a Case into the fem/ objects it describes: part shape, mesh, material, stress profile, clamps.
#include "apps/case_file.hpp"
#include "fem/element_operators.hpp"
#include "fem/mesh.hpp"
#include "levelset/part_shape.hpp"
#include "fem/residual_stress.hpp"

#include <vector>

namespace drom::app {

struct PartModel {
  fem::PartShape shape;
  fem::Mesh mesh;
  fem::Material material;
  std::vector<int> degrees;     // the Legendre basis
  fem::StressProfile profile;   // the case's profile in that basis
};

PartModel build_part(const Case& c);
// Dofs fixed by the case's [[clamps]]; throws InputError for a clamp that selects nothing.
std::vector<int> clamp_dofs(const Case& c, const PartModel& part);
fem::ProfileParity parity_of(const Case& c);

}  // namespace drom::app
