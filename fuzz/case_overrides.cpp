// Harness: `--set key=value` overrides (one a line) on the embedded default case (case_file/case.hpp).
// Seeds: the shipped cases' run.quick lists and the overrides the tests and docs use.
#include "case_file/case.hpp"
#include "fuzz/fuzz_input.hpp"

#include <sstream>
#include <vector>

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::vector<std::string> overrides;
  std::istringstream lines(drom::fuzz::as_text(data, size));
  for (std::string line; std::getline(lines, line);) overrides.push_back(line);
  drom::fuzz::expect_clean([&] { drom::case_file::load_case(std::nullopt, overrides); }, {"<embedded default case>", "--set"});
  return 0;
}
