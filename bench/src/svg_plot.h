// A log-log line chart as a standalone SVG file: for "ms against particle
// count" plots that a browser opens without any plotting package.
#pragma once

#include <string>
#include <utility>
#include <vector>

namespace sluice::bench {

struct PlotSeries {
  std::string name;
  std::vector<std::pair<double, double>> points;  // (x, y), both > 0; drawn in x order
};

// Writes the chart; points with x or y <= 0 are left out. Throws
// std::runtime_error if the file cannot be written or nothing is left to draw.
void write_loglog_svg(const std::string& path, const std::string& title, const std::string& x_label,
                      const std::string& y_label, std::vector<PlotSeries> series);

}  // namespace sluice::bench
