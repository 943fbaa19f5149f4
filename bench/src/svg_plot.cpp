#include "svg_plot.h"

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace sluice::bench {
namespace {

constexpr double kWidth = 720, kHeight = 460, kLeft = 80, kRight = 170, kTop = 50, kBottom = 60;
constexpr const char* kColors[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b"};

std::string escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else out += c;
  }
  return out;
}

// "1M", "10k", "0.1": a power of ten as people write it.
std::string decade_label(int e) {
  if (e >= 9) return std::to_string(int(std::pow(10, e - 9))) + "G";
  if (e >= 6) return std::to_string(int(std::pow(10, e - 6))) + "M";
  if (e >= 3) return std::to_string(int(std::pow(10, e - 3))) + "k";
  if (e >= 0) return std::to_string(int(std::pow(10, e)));
  std::ostringstream s;
  s << std::pow(10.0, e);
  return s.str();
}

}  // namespace

void write_loglog_svg(const std::string& path, const std::string& title, const std::string& x_label,
                      const std::string& y_label, std::vector<PlotSeries> series) {
  double x0 = INFINITY, x1 = -INFINITY, y0 = INFINITY, y1 = -INFINITY;
  for (PlotSeries& s : series) {
    std::erase_if(s.points, [](const auto& p) { return !(p.first > 0 && p.second > 0); });
    std::sort(s.points.begin(), s.points.end());
    for (const auto& [x, y] : s.points) {
      x0 = std::min(x0, x), x1 = std::max(x1, x), y0 = std::min(y0, y), y1 = std::max(y1, y);
    }
  }
  std::erase_if(series, [](const PlotSeries& s) { return s.points.empty(); });
  if (series.empty()) throw std::runtime_error(path + ": nothing to plot");
  const int ex0 = int(std::floor(std::log10(x0))), ex1 = std::max(ex0 + 1, int(std::ceil(std::log10(x1))));
  const int ey0 = int(std::floor(std::log10(y0))), ey1 = std::max(ey0 + 1, int(std::ceil(std::log10(y1))));
  const double pw = kWidth - kLeft - kRight, ph = kHeight - kTop - kBottom;
  auto px = [&](double x) { return kLeft + (std::log10(x) - ex0) / (ex1 - ex0) * pw; };
  auto py = [&](double y) { return kTop + ph - (std::log10(y) - ey0) / (ey1 - ey0) * ph; };

  std::ostringstream svg;
  svg << "<svg xmlns='http://www.w3.org/2000/svg' width='" << kWidth << "' height='" << kHeight
      << "' font-family='sans-serif' font-size='12'>\n<rect width='100%' height='100%' fill='white'/>\n";
  svg << "<text x='" << kWidth / 2 << "' y='24' text-anchor='middle' font-size='15'>" << escape(title) << "</text>\n";
  for (int e = ex0; e <= ex1; ++e) {
    const double x = px(std::pow(10.0, e));
    svg << "<line x1='" << x << "' y1='" << kTop << "' x2='" << x << "' y2='" << kTop + ph << "' stroke='#ddd'/>"
        << "<text x='" << x << "' y='" << kTop + ph + 18 << "' text-anchor='middle'>" << decade_label(e) << "</text>\n";
  }
  for (int e = ey0; e <= ey1; ++e) {
    const double y = py(std::pow(10.0, e));
    svg << "<line x1='" << kLeft << "' y1='" << y << "' x2='" << kLeft + pw << "' y2='" << y << "' stroke='#ddd'/>"
        << "<text x='" << kLeft - 8 << "' y='" << y + 4 << "' text-anchor='end'>" << decade_label(e) << "</text>\n";
  }
  svg << "<rect x='" << kLeft << "' y='" << kTop << "' width='" << pw << "' height='" << ph
      << "' fill='none' stroke='#444'/>\n";
  svg << "<text x='" << kLeft + pw / 2 << "' y='" << kHeight - 16 << "' text-anchor='middle'>" << escape(x_label)
      << "</text>\n<text transform='translate(22," << kTop + ph / 2 << ") rotate(-90)' text-anchor='middle'>"
      << escape(y_label) << "</text>\n";
  for (size_t i = 0; i < series.size(); ++i) {
    const char* color = kColors[i % std::size(kColors)];
    svg << "<polyline fill='none' stroke='" << color << "' stroke-width='2' points='";
    for (const auto& [x, y] : series[i].points) svg << px(x) << ',' << py(y) << ' ';
    svg << "'/>\n";
    for (const auto& [x, y] : series[i].points) {
      svg << "<circle cx='" << px(x) << "' cy='" << py(y) << "' r='3.5' fill='" << color << "'/>\n";
    }
    const double ly = kTop + 10 + 20 * double(i);
    svg << "<line x1='" << kLeft + pw + 14 << "' y1='" << ly << "' x2='" << kLeft + pw + 34 << "' y2='" << ly
        << "' stroke='" << color << "' stroke-width='2'/><text x='" << kLeft + pw + 40 << "' y='" << ly + 4 << "'>"
        << escape(series[i].name) << "</text>\n";
  }
  svg << "</svg>\n";
  std::ofstream out(path);
  out << svg.str();
  if (!out) throw std::runtime_error(path + ": cannot write");
}

}  // namespace sluice::bench
