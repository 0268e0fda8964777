// PNG plots through Debian's matplotlib: a file that is a PNG, written atomically, or a clear "no".
#include "support/png_plot.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>

TEST(PngPlot, WritesAPngWithItsCurvesOrSaysItCannot) {
  drom::PlotSpec spec;
  spec.title = "error over passes";
  spec.x_label = "pass";
  spec.y_label = "max error (mm)";
  drom::PlotSeries s{"without correction", {}, {}, "o-"};
  for (int i = 1; i <= 10; ++i) s.x.push_back(i), s.y.push_back(0.01 * i);
  s.y[3] = std::nan("");  // a gap, not a failure
  spec.series.push_back(s);
  spec.hlines.emplace_back("tolerance", 0.05);
  const auto png = std::filesystem::temp_directory_path() / "drom_plot_test.png";
  std::filesystem::remove(png);
  const bool written = drom::write_png_plot(png, spec);
  if (std::system("/usr/bin/python3 -c 'import matplotlib' >/dev/null 2>&1") != 0) {
    EXPECT_FALSE(written);
    GTEST_SKIP() << "no /usr/bin/python3 with matplotlib here: scripts/setup installs python3-matplotlib";
  }
  ASSERT_TRUE(written);
  std::ifstream in(png, std::ios::binary);
  char sig[8] = {};
  in.read(sig, 8);
  EXPECT_EQ(std::string(sig + 1, 3), "PNG");
  EXPECT_GT(std::filesystem::file_size(png), 10000u);
  for (const auto& e : std::filesystem::directory_iterator(png.parent_path())) EXPECT_EQ(e.path().string().find("drom_plot_test.png.tmp"), std::string::npos);
  std::filesystem::remove(png);
}
