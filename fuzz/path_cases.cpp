// Harness: the toolpath side's case files, all read through support/toml_reader.hpp: the finishing
// case (paths/finish/finish_case.hpp, with its [surface] from geometry/surface_input.hpp), the copy settings
// (paths/copy/copy_settings.hpp) and the orientation case (paths/orient/orient_run.hpp). The first byte picks the
// reader, so one corpus mixes the three and the mutator carries keys across them. Seeds: cases/*.toml
// of each kind and the default copy settings.
#include "fuzz/fuzz_input.hpp"
#include "paths/copy/copy_settings.hpp"
#include "paths/finish/finish_case.hpp"
#include "paths/orient/orient_run.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  if (size == 0) return 0;
  const std::uint8_t reader = data[0] % 3;
  ++data, --size;
  if (reader == 0) {
    const auto file = drom::fuzz::as_file(data, size, "fuzz_finish.toml");
    drom::fuzz::expect_clean([&] { drom::paths::load_finish_case(file, {}); }, file.string());
  } else if (reader == 1) {
    const std::string origin = "fuzz_copy.toml";
    drom::fuzz::expect_clean([&] { drom::paths::read_copy_settings(drom::fuzz::as_text(data, size), origin); }, origin);
  } else {
    const std::string origin = "fuzz_orient.toml";
    drom::fuzz::expect_clean([&] { drom::paths::parse_orient_case(drom::fuzz::as_text(data, size), origin); }, origin);
  }
  return 0;
}
