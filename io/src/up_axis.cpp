// Up-axis detection (see up_axis.h for the rules and their order).
#include "sluice/io/up_axis.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

namespace sluice::io {
namespace {

constexpr size_t kShapeSamples = 65536;
constexpr const char* kAxisNames = "xyz";

std::string figure(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3g", v);
  return buf;
}

// The median, reordering `values` (not empty).
double median(std::vector<double>& values) {
  const auto mid = values.begin() + values.size() / 2;
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

}  // namespace

int up_axis_index(UpAxis up) {
  switch (up) {
    case UpAxis::PosX:
    case UpAxis::NegX: return 0;
    case UpAxis::PosY:
    case UpAxis::NegY: return 1;
    default: return 2;
  }
}

bool up_axis_negative(UpAxis up) { return up == UpAxis::NegX || up == UpAxis::NegY || up == UpAxis::NegZ; }

std::array<float, 3> up_vector(UpAxis up) {
  std::array<float, 3> v{0, 0, 0};
  v[up_axis_index(up)] = up_axis_negative(up) ? -1.0f : 1.0f;
  return v;
}

std::string up_axis_name(UpAxis up) {
  const char name[3] = {up_axis_negative(up) ? '-' : '+', kAxisNames[up_axis_index(up)], '\0'};
  return name;
}

const char* up_evidence_name(UpEvidence e) {
  switch (e) {
    case UpEvidence::Given: return "given";
    case UpEvidence::Motion: return "motion";
    case UpEvidence::Pressure: return "pressure";
    case UpEvidence::Shape: return "shape";
    case UpEvidence::Default: return "default";
    default: return "unstated";
  }
}

UpAxis up_axis_from(int axis, bool negative) {
  return static_cast<UpAxis>(1 + std::clamp(axis, 0, 2) + (negative ? 3 : 0));
}

std::optional<UpAxis> parse_up_axis(std::string_view text) {
  bool negative = false;
  if (!text.empty() && (text[0] == '+' || text[0] == '-')) {
    negative = text[0] == '-';
    text.remove_prefix(1);
  }
  if (text.size() != 1) return std::nullopt;
  const char c = char(std::tolower(static_cast<unsigned char>(text[0])));
  if (c < 'x' || c > 'z') return std::nullopt;
  return up_axis_from(c - 'x', negative);
}

FrameShape measure_shape(std::span<const float> xyz, const ShapeGrid* grid) {
  FrameShape s;
  const size_t n = xyz.size() / 3;
  s.particles = n;
  if (n == 0) return s;
  const size_t stride = std::max<size_t>(1, n / kShapeSamples);
  std::vector<float> values;
  values.reserve(n / stride + 1);
  for (int a = 0; a < 3; ++a) {
    values.clear();
    for (size_t i = 0; i < n; i += stride) values.push_back(xyz[3 * i + a]);
    const size_t lo = values.size() / 200, hi = values.size() - 1 - values.size() / 200;
    std::nth_element(values.begin(), values.begin() + lo, values.end());
    s.low[a] = values[lo];
    std::nth_element(values.begin(), values.begin() + hi, values.end());
    s.high[a] = values[hi];
  }
  if (grid == nullptr || grid->box.empty()) return s;
  const std::array<int, 3> cells = grid->cells();
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::array<float, 3> scale{};
  for (int a = 0; a < 3; ++a) {
    const int u = (a + 1) % 3, v = (a + 2) % 3;
    s.column_low[a].assign(size_t(cells[u]) * cells[v], nan);
    s.column_high[a].assign(size_t(cells[u]) * cells[v], nan);
    const float extent = grid->box.max[a] - grid->box.min[a];
    scale[a] = extent > 0 ? float(cells[a]) / extent : 0.0f;
  }
  for (size_t i = 0; i < n; ++i) {
    std::array<int, 3> cell{};
    std::array<bool, 3> inside{};
    for (int a = 0; a < 3; ++a) {
      const float c = (xyz[3 * i + a] - grid->box.min[a]) * scale[a];
      inside[a] = c >= 0 && c < float(cells[a]);
      cell[a] = inside[a] ? int(c) : 0;
    }
    for (int a = 0; a < 3; ++a) {
      // The column along a is picked by the other two axes, even where the
      // particle lies outside the box along a.
      const int u = (a + 1) % 3, v = (a + 2) % 3;
      if (!inside[u] || !inside[v]) continue;
      const size_t column = size_t(cell[u]) * cells[v] + size_t(cell[v]);
      const float x = xyz[3 * i + a];
      float& low = s.column_low[a][column];
      float& high = s.column_high[a][column];
      if (!(low <= x)) low = x;
      if (!(high >= x)) high = x;
    }
  }
  return s;
}

std::array<int, 3> ShapeGrid::cells() const {
  std::array<int, 3> n{1, 1, 1};
  for (int a = 0; a < 3; ++a) {
    const float extent = box.max[a] - box.min[a];
    if (extent > 0 && cell > 0) n[a] = std::clamp(int(extent / cell), 1, kShapeColumns);
    else if (extent > 0) n[a] = kShapeColumns;
  }
  return n;
}

std::optional<UpFinding> up_from_motion(std::span<const FrameShape> frames, float spacing) {
  // Degenerate frames (a handful of particles, or all at one point: a
  // solver's empty or broken output) say nothing about a fall.
  const auto degenerate = [](const FrameShape& f) {
    float extent = 0;
    for (int a = 0; a < 3; ++a) extent = std::max(extent, f.high[a] - f.low[a]);
    return f.particles < kLeastShapeParticles || !(extent > 0);
  };
  std::vector<const FrameShape*> used;
  for (const FrameShape& f : frames) {
    if (!degenerate(f) && !f.column_low[0].empty()) used.push_back(&f);
  }
  if (used.size() < 2) return std::nullopt;
  const FrameShape& first = *used.front();
  float extent = 0;
  for (int a = 0; a < 3; ++a) extent = std::max(extent, first.high[a] - first.low[a]);
  const double unit = spacing > 0 ? spacing : 0.01 * extent;
  if (!(unit > 0)) return std::nullopt;
  // For direction d (axis, sign), a column's trailing end is its lowest
  // coordinate along d and its leading end its highest: how far each moved
  // along d, the median over the columns filled in both frames (a median,
  // because a fluid that rises on one side and falls on the other empties
  // the top rows of the columns across, whose ends then jump), in the frame
  // where the trailing ends moved most.
  std::array<double, 6> moved{}, leading{};
  std::vector<double> trail_moves, lead_moves;
  for (int d = 0; d < 6; ++d) {
    const int axis = d % 3;
    const bool negative = d >= 3;
    const std::vector<float>& trail0 = negative ? first.column_high[axis] : first.column_low[axis];
    const std::vector<float>& lead0 = negative ? first.column_low[axis] : first.column_high[axis];
    const double sign = negative ? -1.0 : 1.0;
    moved[d] = -std::numeric_limits<double>::infinity();
    for (size_t f = 1; f < used.size(); ++f) {
      const std::vector<float>& trail = negative ? used[f]->column_high[axis] : used[f]->column_low[axis];
      const std::vector<float>& lead = negative ? used[f]->column_low[axis] : used[f]->column_high[axis];
      std::vector<double>& tr = trail_moves;
      std::vector<double>& ld = lead_moves;
      tr.clear();
      ld.clear();
      for (size_t c = 0; c < trail0.size(); ++c) {
        if (std::isnan(trail0[c]) || std::isnan(trail[c])) continue;
        tr.push_back(sign * (double(trail[c]) - trail0[c]));
        ld.push_back(sign * (double(lead[c]) - lead0[c]));
      }
      if (tr.empty()) continue;
      const double trail_median = median(tr), lead_median = median(ld);
      if (trail_median > moved[d]) {
        moved[d] = trail_median;
        leading[d] = lead_median;
      }
    }
    if (!std::isfinite(moved[d])) moved[d] = 0;
  }
  const int best = int(std::max_element(moved.begin(), moved.end()) - moved.begin());
  double second = 0;
  for (int d = 0; d < 6; ++d) {
    if (d != best) second = std::max(second, moved[d]);
  }
  if (moved[best] < 0.5 * unit || moved[best] < 3 * second) return std::nullopt;
  // A fall lands on a floor that stays; a fluid that moves as a whole (a
  // sway, a drift, a free fall) moves both ends alike and is not evidence.
  if (std::abs(leading[best]) > moved[best] / 3) return std::nullopt;
  // The fall is along direction `best`; up is the other way.
  UpFinding f;
  f.up = up_axis_from(best % 3, best < 3);
  f.evidence = UpEvidence::Motion;
  const std::string fall = up_axis_name(up_axis_from(best % 3, best >= 3));
  f.reason = "the fluid's top falls toward " + fall + " over the first " + std::to_string(used.size()) +
             " frames (by " + figure(moved[best]) + " in the median column, " + figure(moved[best] / unit) +
             " spacings, while its floor moved " + figure(leading[best]) + "; no other direction more than " +
             figure(std::max(second, 0.0)) + ")";
  return f;
}

std::optional<UpFinding> up_from_pressure(std::span<const float> xyz, std::span<const float> values,
                                          std::string_view array_name) {
  const size_t n = std::min(xyz.size() / 3, values.size());
  if (n < 16) return std::nullopt;
  const size_t stride = std::max<size_t>(1, n / kShapeSamples);
  // Least squares of value against centred position: solve C b = r.
  double mean[4] = {0, 0, 0, 0};
  size_t m = 0;
  for (size_t i = 0; i < n; i += stride, ++m) {
    for (int a = 0; a < 3; ++a) mean[a] += xyz[3 * i + a];
    mean[3] += values[i];
  }
  for (double& v : mean) v /= double(m);
  double c[3][3] = {}, r[3] = {}, total = 0;
  for (size_t i = 0; i < n; i += stride) {
    const double d[3] = {xyz[3 * i] - mean[0], xyz[3 * i + 1] - mean[1], xyz[3 * i + 2] - mean[2]};
    const double v = values[i] - mean[3];
    for (int a = 0; a < 3; ++a) {
      r[a] += d[a] * v;
      for (int b = 0; b < 3; ++b) c[a][b] += d[a] * d[b];
    }
    total += v * v;
  }
  // Cramer's rule on the 3x3 system.
  const auto det3 = [](const double k[3][3]) {
    return k[0][0] * (k[1][1] * k[2][2] - k[1][2] * k[2][1]) - k[0][1] * (k[1][0] * k[2][2] - k[1][2] * k[2][0]) +
           k[0][2] * (k[1][0] * k[2][1] - k[1][1] * k[2][0]);
  };
  const double det = det3(c);
  if (!(std::abs(det) > 0) || !(total > 0)) return std::nullopt;
  double g[3];
  for (int col = 0; col < 3; ++col) {
    double k[3][3];
    for (int a = 0; a < 3; ++a) {
      for (int b = 0; b < 3; ++b) k[a][b] = b == col ? r[a] : c[a][b];
    }
    g[col] = det3(k) / det;
  }
  const double explained = (g[0] * r[0] + g[1] * r[1] + g[2] * r[2]) / total;  // R^2 of the fit
  const double norm = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
  if (!(norm > 0) || !std::isfinite(explained)) return std::nullopt;
  int axis = 0;
  for (int a = 1; a < 3; ++a) {
    if (std::abs(g[a]) > std::abs(g[axis])) axis = a;
  }
  const double alignment = std::abs(g[axis]) / norm;  // cos of the angle to the axis
  if (explained < 0.2 || alignment < std::cos(25.0 * 3.14159265358979 / 180.0)) return std::nullopt;
  UpFinding f;
  f.up = up_axis_from(axis, g[axis] > 0);  // it grows with depth: up is against the gradient
  f.evidence = UpEvidence::Pressure;
  f.reason = std::string(array_name);
  f.reason.insert(0, 1, '\'');
  f.reason += "' grows toward " + up_axis_name(up_axis_from(axis, g[axis] < 0)) +
              " as with depth in a resting fluid (a linear fit explains " + figure(100 * explained) + "% of its variance)";
  return f;
}

std::optional<UpFinding> up_from_shape(const FrameShape& s) {
  if (s.particles == 0) return std::nullopt;
  std::array<float, 3> e{};
  for (int a = 0; a < 3; ++a) e[a] = s.high[a] - s.low[a];
  const int thin = int(std::min_element(e.begin(), e.end()) - e.begin());
  for (int a = 0; a < 3; ++a) {
    if (a != thin && !(e[thin] < 0.5f * e[a])) return std::nullopt;
  }
  UpFinding f;
  f.up = up_axis_from(thin, false);
  f.evidence = UpEvidence::Shape;
  f.reason = "the fluid lies flat, thinnest along " + std::string(1, kAxisNames[thin]) + " (" + figure(e[thin]) +
             " against " + figure(e[(thin + 1) % 3]) + " and " + figure(e[(thin + 2) % 3]) +
             "); which way along it is assumed";
  return f;
}

std::string pick_pressure_array(std::span<const std::string> arrays) {
  static constexpr const char* kNames[] = {"p",   "pressure", "Pressure", "Press",   "PRESSURE",
                                           "rho", "Rho",      "Rhop",     "density", "Density"};
  for (const char* name : kNames) {
    if (std::find(arrays.begin(), arrays.end(), name) != arrays.end()) return name;
  }
  return {};
}

}  // namespace sluice::io
