#include "loop/deviation_case.hpp"

#include "support/toml_reader.hpp"
#include "support/input_error.hpp"


namespace drom::loop {

namespace {

reduce::DeviationRange range(TomlReader& r, const std::string& key, Range values) {
  if (!r.has(key)) return {};
  const auto v = r.reals(key, Range{});
  if (v.size() != 3) r.fail(key, "expected [min, max, count]");
  if (v[2] < 0 || v[2] != static_cast<double>(static_cast<int>(v[2])) || v[2] > 1000) r.fail(key, "the count (third value) must be a whole number from 0 to 1000");
  if (v[2] > 0 && (!values.contains(v[0]) || !values.contains(v[1]))) r.fail(key, "min and max must be " + values.describe());
  if (v[1] < v[0]) r.fail(key, "max must not be below min");
  return {v[0], v[1], static_cast<int>(v[2])};
}

std::filesystem::path relative_to(const std::string& origin, const std::string& file) {
  std::filesystem::path p(file);
  return p.is_absolute() ? p : std::filesystem::path(origin).parent_path() / p;
}

}  // namespace

DeviationCase load_deviation_case(const std::filesystem::path& path, const std::vector<std::string>& overrides) {
  TomlReader r(read_input_file(path, "case file"), path.string(), overrides);
  DeviationCase c;
  c.origin = path.string();
  c.name = r.text("name");
  c.description = r.text("description", "");
  c.grid.x0 = r.real("area.x_min", Range{});
  c.grid.x1 = r.real("area.x_max", Range{});
  c.grid.y0 = r.real("area.y_min", Range{});
  c.grid.y1 = r.real("area.y_max", Range{});
  if (c.grid.x1 <= c.grid.x0) r.fail("area.x_max", "must exceed area.x_min");
  if (c.grid.y1 <= c.grid.y0) r.fail("area.y_max", "must exceed area.y_min");
  c.grid.nx = c.grid.ny = static_cast<int>(r.integer("area.grid", 3, 1001, 101));
  c.nominal_z = r.real("area.nominal_z", Range{}, 0.0);
  c.seed_a = range(r, "family.seed_a", Range{});
  c.seed_b = range(r, "family.seed_b", Range::positive());
  c.bending_x = range(r, "family.bending_x_radius", Range::positive());
  c.bending_y = range(r, "family.bending_y_radius", Range::positive());
  c.twist = range(r, "family.twist", Range{});
  c.offset = range(r, "family.offset", Range{});
  c.tilt_x = range(r, "family.tilt_x", Range::closed(-0.1, 0.1));
  c.tilt_y = range(r, "family.tilt_y", Range::closed(-0.1, 0.1));
  if ((c.seed_a.count > 0) != (c.seed_b.count > 0)) r.fail("family.seed_b", "the seed's family needs both seed_a and seed_b (or neither)");
  if (r.has("family.measured"))
    for (const auto& f : r.strings("family.measured")) c.measured.push_back(relative_to(c.origin, f));
  c.family_tolerance = r.real("family.tolerance", Range::positive(), 1e-3);
  c.truth = r.choice("truth.surface", {"seed", "csv"}, "seed");
  if (c.truth == "csv") c.truth_csv = relative_to(c.origin, r.text("truth.csv"));
  const auto offset = r.reals("sensor.offset", Range{}, std::vector<double>{20, 0, 80});
  if (offset.size() != 3) r.fail("sensor.offset", "expected [x, y, z]");
  c.sheet.offset = {offset[0], offset[1], offset[2]};
  c.sheet.angle_deg = r.real("sensor.angle", Range::closed(-180, 180), 45);
  c.sheet.length = r.real("sensor.length", Range::positive(), 80);
  c.sheet.points = static_cast<int>(r.integer("sensor.points", 2, 100000, 800));
  c.period = r.real("sensor.period", Range::positive(), 0.1);
  c.errors.noise_sd = r.real("sensor.noise", Range::non_negative(), 0.05);
  const auto oe = r.reals("sensor.offset_error", Range{}, std::vector<double>{0, 0, 0});
  if (oe.size() != 3) r.fail("sensor.offset_error", "expected [x, y, z]");
  c.errors.offset_error = {oe[0], oe[1], oe[2]};
  c.errors.angle_error_deg = r.real("sensor.angle_error", Range::closed(-90, 90), 0);
  c.desync = r.real("sensor.desync", Range::non_negative(), 0);
  c.feed_override = r.real("sensor.feed_override", Range::open(0, 10), 1);
  c.feed = r.real("path.feed", Range::positive(), 10);
  c.stepover = r.real("path.stepover", Range::positive());
  c.approach_x = r.reals("path.approach_x", Range{});
  c.approach_y = r.reals("path.approach_y", Range{});
  if (c.approach_x.size() != c.approach_y.size() || c.approach_x.empty()) r.fail("path.approach_y", "approach_x and approach_y must list the same number (>= 1) of waypoints");
  c.learning_tolerance = r.real("learning.tolerance", Range::positive(), 0.01);
  c.learning_window = static_cast<int>(r.integer("learning.window", 1, 1000, 5));
  c.path_tolerance = r.real("learning.path_tolerance", Range::positive(), 0.02);
  r.finish();
  c.resolved_toml = r.resolved_text();
  return c;
}

}  // namespace drom::loop
