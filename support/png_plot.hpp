#pragma once
// Curves as PNG for people who would rather look than read (the CSV beside it holds the numbers).
// Rendered by matplotlib from Debian's python3-matplotlib (installed by scripts/setup): the script
// is compiled into drom and run with /usr/bin/python3. Where python3 or matplotlib is missing, no
// PNG is written and the call says so (the CSV is the record; a plot is a convenience).
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

namespace drom {

struct PlotSeries {
  std::string name;
  std::vector<double> x, y;
  std::string style = "-";  // matplotlib format: "-", "o-", "--", ...
};

// A colour map of values on a regular grid (row j = y index), drawn under the series.
struct PlotMap {
  double x0 = 0, x1 = 1, y0 = 0, y1 = 1;
  int nx = 0, ny = 0;
  std::vector<double> values;  // ny x nx, row-major; NaN: blank
  std::string label, colormap = "viridis";
};

struct PlotSpec {
  std::string title, x_label, y_label;
  std::vector<PlotSeries> series;
  std::vector<std::pair<std::string, double>> hlines;  // named horizontal lines (tolerances)
  bool log_y = false;
  std::optional<PlotMap> map;
};

// Writes the PNG atomically; returns false (and writes nothing) if it cannot be rendered here.
bool write_png_plot(const std::filesystem::path& png, const PlotSpec& spec);

}  // namespace drom
