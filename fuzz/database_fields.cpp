// Harness: a snapshot database that is sealed and valid HDF5 but whose content is wrong
// (fuzz/hdf5_fields.hpp), reduced as drom reduce does (reduce/database_reduction.hpp), with the
// stock's top kept. Base: the flat plate's coarse database written by drom_fuzz_seeds.
#include "fuzz/hdf5_fields.hpp"
#include "reduce/database_reduction.hpp"

namespace {
const drom::fuzz::Hdf5Content& base() {
  static const auto content = drom::fuzz::read_content(DROM_FUZZ_BASE_DIR "/database.h5");
  return content;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = drom::fuzz::edited_file(base(), data, size, "fuzz_database.h5");
  drom::reduce::DatabaseReductionSettings settings;
  settings.top_margin = 50;
  drom::fuzz::expect_clean(
      [&] {
        const auto reduced = drom::reduce::reduce_database(file, settings);
        drom::fuzz::require(reduced.model.error_bound() >= 0 && std::isfinite(reduced.model.error_bound()), "a reduction whose error bound is not a finite bound");
      },
      file.string());
  return 0;
}
