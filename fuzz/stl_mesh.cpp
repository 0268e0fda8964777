// Harness: an STL workpiece read (geometry/closed_surface.hpp), then TetGen on what the reader accepts
// when small (fem/tet_mesh.hpp, as part.shape = "stl" does): whatever passes the reader's checks must
// mesh, or fail with a message naming TetGen. Seeds: the stl harness's.
#include "fem/tet_mesh.hpp"
#include "fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = drom::fuzz::as_file(data, size, "fuzz_part.stl");
  drom::fuzz::expect_clean(
      [&] {
        const auto plc = drom::fem::read_closed_stl(file);
        if (plc.facets.size() <= 64) {
          const auto mesh = drom::fem::make_tet_mesh(plc, {});
          drom::fuzz::require(mesh.element_count() > 0, "TetGen accepted a surface and gave no element");
        }
      },
      {file.string(), "TetGen"});
  return 0;
}
