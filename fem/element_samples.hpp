#pragma once
// A mesh's elements as levelset/ sees them: centroid, bounds and weighted quadrature points.
#include "fem/mesh.hpp"
#include "levelset/material_removal.hpp"

namespace drom::fem {

// Sample points no farther apart than about `spacing`, per element and direction (thin elements
// stay cheap): a uniform midpoint grid on hexahedra, a Gauss rule on tetrahedra. Weights are
// |J| w and sum to each element's volume.
levelset::ElementSamples element_samples(const Mesh& mesh, double spacing);

}  // namespace drom::fem
