// Harness: a blank-deviation case file (loop/deviation_case.hpp). Seeds: cases/deviation.toml.
#include "fuzz/fuzz_input.hpp"
#include "loop/deviation_case.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = drom::fuzz::as_file(data, size, "fuzz_deviation.toml");
  drom::fuzz::expect_clean([&] { drom::loop::load_deviation_case(file, {}); }, file.string());
  return 0;
}
