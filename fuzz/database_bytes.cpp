// Harness: the snapshot database's bytes, truncated or flipped anywhere, through drom reduce
// (reduce/database_reduction.hpp). The seal must refuse every change before libhdf5 reads it. Seed:
// the flat plate's coarse database.
#include "fuzz/fuzz_input.hpp"
#include "reduce/database_reduction.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = drom::fuzz::as_file(data, size, "fuzz_database.h5");
  drom::fuzz::expect_clean([&] { drom::reduce::reduce_database(file, {}); }, file.string());
  return 0;
}
