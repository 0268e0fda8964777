#pragma once
// Curves as PNG for people who would rather look than read (the CSV beside it holds the numbers).
// Rendered by matplotlib from Debian's python3-matplotlib (installed by scripts/setup): the script
// is compiled into drom and run with /usr/bin/python3. Where python3 or matplotlib is missing, no
// PNG is written and the call says so (the CSV is the record; a plot is a convenience).
#include <filesystem>
#include <string>
#include <vector>

namespace drom {

struct PlotSeries {
  std::string name;
  std::vector<double> x, y;
  std::string style = "-";  // matplotlib format: "-", "o-", "--", ...
};

struct PlotSpec {
  std::string title, x_label, y_label;
  std::vector<PlotSeries> series;
  std::vector<std::pair<std::string, double>> hlines;  // named horizontal lines (tolerances)
  bool log_y = false;
};

// Writes the PNG atomically; returns false (and writes nothing) if it cannot be rendered here.
bool write_png_plot(const std::filesystem::path& png, const PlotSpec& spec);

}  // namespace drom
