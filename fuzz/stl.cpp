// Harness: an STL workpiece (geometry/closed_surface.hpp), ASCII or binary, read and checked closed as
// part.shape = "stl" does. TetGen on what it accepts is the stl_mesh harness (a mesh per input is a
// hundred times slower, so the reader's own long run goes without it). Seeds: closed boxes and the
// shipped plate's stock written as STL.
#include "fem/tet_mesh.hpp"
#include "fuzz/fuzz_input.hpp"

#include <cmath>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = drom::fuzz::as_file(data, size, "fuzz_part.stl");
  drom::fuzz::expect_clean(
      [&] {
        const auto plc = drom::fem::read_closed_stl(file);
        drom::fuzz::require(!plc.facets.empty(), "a closed surface without a facet accepted");
      },
      file.string());
  return 0;
}
