// Harness: the model file's bytes, truncated or flipped anywhere (reduce/light_model.hpp). The seal
// (support/file_integrity.hpp) must refuse every change before libhdf5 reads it. Seed: the flat
// plate's coarse model.
#include "fuzz/fuzz_input.hpp"
#include "reduce/light_model.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = drom::fuzz::as_file(data, size, "fuzz_model.h5");
  drom::fuzz::expect_clean([&] { drom::reduce::LightModel::read(file); }, file.string());
  return 0;
}
