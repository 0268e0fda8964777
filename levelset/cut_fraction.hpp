#pragma once
// The share of a tetrahedron where a linear function is negative, from its four vertex values.
// Exact: the region is a corner tetrahedron, or a prism whose quadrilateral faces lie in the
// tetrahedron's faces and in the zero plane. It does not depend on the tetrahedron's shape (an affine
// map keeps volume ratios), so it serves the sub-cells of any element in reference coordinates.
namespace drom::levelset {

// Vertex values f0..f3 of the linear function; a value of exactly 0 counts as non-negative.
double negative_fraction(double f0, double f1, double f2, double f3);

}  // namespace drom::levelset
