// Harness: a case file (case_file/case.hpp, through support/toml_reader.hpp). Seeds: cases/*.toml.
#include "case_file/case.hpp"
#include "fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string origin = "fuzz_case.toml";
  drom::fuzz::expect_clean([&] { drom::case_file::case_from_text(drom::fuzz::as_text(data, size), origin); }, origin);
  return 0;
}
