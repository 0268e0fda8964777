// Harness: a face of a STEP file (geometry/step_face.hpp, OpenCASCADE's reader underneath), as a
// finishing case's `step = "file.step"` reads it: the face count, then face 1 as drom's NURBS patch.
// Seeds: a Bézier patch, a trimmed plane and a vertex-only file, written with OpenCASCADE.
#include "fuzz/fuzz_input.hpp"
#include "geometry/step_face.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = drom::fuzz::as_file(data, size, "fuzz_face.step");
  drom::fuzz::expect_clean(
      [&] {
        const int faces = drom::geometry::count_step_faces(file);
        drom::fuzz::require(faces >= 1, "a face count below 1 returned instead of an error");
        const auto face = drom::geometry::read_step_face(file, 1);
        const auto p = face.surface.point(0.5, 0.5);
        drom::fuzz::require(p.allFinite(), "a face whose surface evaluates to a non-finite point");
      },
      file.string());
  return 0;
}
