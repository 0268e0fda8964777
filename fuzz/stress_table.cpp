// Harness: a measured stress-profile table (fem/residual_stress.hpp), read and fitted as the offline
// job does (the flat plate's 10 mm, even degrees to 6). Seeds: the shipped cases' profiles as tables.
#include "fem/residual_stress.hpp"
#include "fuzz/fuzz_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = drom::fuzz::as_file(data, size, "fuzz_stress.csv");
  drom::fuzz::expect_clean(
      [&] {
        const auto table = drom::fem::read_profile_table(file);
        const auto profile = drom::fem::fit_profile(table, 10.0, {2, 4, 6});
        for (std::size_t j = 0; j < profile.degrees.size(); ++j)
          drom::fuzz::require(std::isfinite(profile.sigma11[j]) && std::isfinite(profile.sigma22[j]), "a fitted profile with a non-finite coefficient");
      },
      file.string());
  return 0;
}
