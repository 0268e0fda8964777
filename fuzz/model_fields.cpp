// Harness: a light model that is sealed and valid HDF5 but whose content is wrong (fuzz/hdf5_fields.hpp),
// read (reduce/light_model.hpp) and loaded by the online predictor as drom run and the Python module do.
// Base: the flat plate's coarse model written by drom_fuzz_seeds.
#include "fuzz/hdf5_fields.hpp"
#include "online/predictor.hpp"
#include "reduce/light_model.hpp"

namespace {
const drom::fuzz::Hdf5Content& base() {
  static const auto content = drom::fuzz::read_content(DROM_FUZZ_BASE_DIR "/model.h5");
  return content;
}
}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = drom::fuzz::edited_file(base(), data, size, "fuzz_model.h5");
  drom::fuzz::expect_clean(
      [&] {
        // Path samples every 50 mm, not drom run's 2: the same code runs on every field of the model,
        // and loading the predictor stops being most of an input's time.
        drom::online::PredictorSettings settings;
        settings.path_sample = 50.0;
        drom::online::Predictor predictor(drom::reduce::LightModel::read(file), settings);
        drom::fuzz::require(std::isfinite(predictor.max_offset()), "a model whose offset bound is not finite");
        const double offset = predictor.tool_offset(1.0);
        drom::fuzz::require(std::isfinite(offset), "a model that commands a non-finite offset");
      },
      file.string());
  return 0;
}
