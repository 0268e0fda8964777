#pragma once
// Faces of a user's CAD part, read from a STEP file with OpenCASCADE: the face's surface as a NURBS
// patch on [0, 1]^2 (whatever its type in the file: B-spline, Bézier, plane, cylinder, ...), and its
// trimming loops in that unit domain. OpenCASCADE is used here only: what leaves this header is
// drom's own types, so path planning evaluates the surface with its own code.
#include "geometry/nurbs_surface.hpp"
#include "geometry/trim_loops.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace drom::geometry {

struct StepFace {
  NurbsSurface surface;     // the face's surface restricted to its UV bounds, domain [0, 1]^2
  TrimLoops trim;           // empty when the face covers its whole UV rectangle
  std::string source_type;  // the surface type in the file (OpenCASCADE's class name)
  bool reversed = false;    // the face's orientation in its shell reverses the surface normal
};

// Number of faces in the file (throws InputError naming the file when it cannot be read).
int count_step_faces(const std::filesystem::path& path);

// Face `index` (1-based, in the order OpenCASCADE explores the shape). Throws InputError naming the
// file when it is missing, unreadable, holds no face, or has fewer faces than `index`.
StepFace read_step_face(const std::filesystem::path& path, int index);

}  // namespace drom::geometry
