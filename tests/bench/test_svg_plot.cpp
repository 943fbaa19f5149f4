// The benchmark's SVG chart: points land where a log-log axis puts them,
// one polyline per series, bad points left out, nothing to draw is an error.
#include <gtest/gtest.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include "svg_plot.h"

namespace sluice::bench {
namespace {

std::string read_all(const std::string& path) {
  std::ifstream in(path);
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

std::string temp_svg() {
  return (std::filesystem::temp_directory_path() / ("sluice_plot_" + std::to_string(::getpid()) + ".svg")).string();
}

TEST(SvgPlot, OnePolylinePerSeriesWithPointsOnALogScale) {
  const std::string path = temp_svg();
  write_loglog_svg(path, "t <&>", "particles", "ms",
                   {{"a", {{1e6, 1.0}, {1e7, 10.0}, {1e8, 100.0}}}, {"b", {{1e6, 0.5}, {1e8, -1.0}}}, {"empty", {}}});
  const std::string svg = read_all(path);
  std::filesystem::remove(path);
  EXPECT_NE(svg.find("t &lt;&amp;&gt;"), std::string::npos);  // escaped title
  const std::regex polyline("<polyline[^>]*points='([^']*)'");
  std::vector<std::string> lines;
  for (auto it = std::sregex_iterator(svg.begin(), svg.end(), polyline); it != std::sregex_iterator(); ++it) {
    lines.push_back((*it)[1]);
  }
  ASSERT_EQ(lines.size(), 2u);  // "empty" and b's negative point are left out
  // Series a: x decades evenly spaced and y rising by the same step (slope 1 on log-log).
  std::istringstream a(lines[0]);
  double x[3], y[3];
  char comma;
  for (int i = 0; i < 3; ++i) a >> x[i] >> comma >> y[i];
  EXPECT_NEAR(x[1] - x[0], x[2] - x[1], 0.01);  // SVG coordinates carry 6 digits
  EXPECT_NEAR(y[0] - y[1], y[1] - y[2], 0.01);
  EXPECT_GT(y[0], y[2]);  // larger values are higher up (smaller SVG y)
  EXPECT_EQ(std::count(lines[1].begin(), lines[1].end(), ','), 1);
}

TEST(SvgPlot, NothingToDrawIsAnError) {
  EXPECT_THROW(write_loglog_svg(temp_svg(), "t", "x", "y", {{"a", {{0.0, 1.0}}}}), std::runtime_error);
}

}  // namespace
}  // namespace sluice::bench
