#pragma once
// A free-form surface declared in a TOML file: a [surface] table with a Bézier, B-spline or NURBS
// control net, or a face of a STEP file. Any module reading a case (paths/, case_file/) calls this with
// its own TomlReader, so geometry/ depends on support/ only. Keys: docs/case-files.md (finishing).
#include "geometry/nurbs_surface.hpp"
#include "geometry/trim_loops.hpp"
#include "support/toml_reader.hpp"

#include <filesystem>
#include <string>

namespace drom::geometry {

struct SurfaceInput {
  NurbsSurface surface;     // domain [0, 1]^2
  TrimLoops trim;           // a trimmed STEP face's loops; empty otherwise
  std::string kind;         // bezier, bspline, nurbs, step
  std::string description;  // for summaries: "Bézier 3 x 3", "face 2 of part.step (Geom_BSplineSurface)"
  std::filesystem::path step_file;
  int face = 0;
};

// Reads `<table>.*` (table is "surface" in a finishing case). Relative STEP paths are taken from
// `base_dir`. Errors (bad keys, an inconsistent net, a degenerate patch, a missing or faceless STEP
// file) throw InputError naming the file, the line and the key.
SurfaceInput read_surface(TomlReader& reader, const std::string& table, const std::filesystem::path& base_dir);

}  // namespace drom::geometry
