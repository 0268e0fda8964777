// Harness: a measured blank surface, "x,y,z" lines (reduce/deviation_family.hpp), sampled onto the
// deviation case's grid. Seeds: the seed's true surface of chapter 2 sampled as a measurement.
#include "fuzz/fuzz_input.hpp"
#include "reduce/deviation_family.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = drom::fuzz::as_file(data, size, "fuzz_surface.csv");
  drom::fuzz::expect_clean(
      [&] {
        drom::reduce::DeviationFamily family(drom::reduce::DeviationGrid{0, 100, 0, 100, 11, 11});
        family.add_measured(file);
        drom::fuzz::require(family.snapshots().allFinite(), "a measured surface sampled to non-finite values");
      },
      file.string());
  return 0;
}
